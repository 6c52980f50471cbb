// libFuzzer harness of the result-document readers (io/documents.h: every "type" ctid writes;
// io/result_json.h: a fitted model for validate/simulate). A document that was read must be
// written (to_json) and read back.
#include "ctid/io/documents.h"
#include "ctid/io/json.h"
#include "ctid/io/result_json.h"
#include "harness.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  return ctid::fuzz::refuse_or_read(data, size, [](std::string_view text) {
    const nlohmann::json document = ctid::io::parse_json(text, "fuzz.json");
    ctid::fuzz::refuse_or_use(document, [](const nlohmann::json& value) {
      const ctid::io::ResultDocument result = ctid::io::result_from_json(value, "fuzz.json");
      ctid::fuzz::must_read_back(
          [&] { (void)ctid::io::result_from_json(ctid::io::to_json(result), "again.json"); });
    });
    ctid::fuzz::refuse_or_use(document, [](const nlohmann::json& value) {
      (void)ctid::io::fitted_model_from_json(value, "fuzz.json");
    });
  });
}
