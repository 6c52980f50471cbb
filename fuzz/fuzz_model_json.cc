// libFuzzer harness of the model readers (io/model_json.h): continuous models (transfer
// function, additive, delayed-feedback loop), MIMO additive models and discrete controllers,
// each on the same parsed document. A model that was read must be written (to_json) and read
// back: ctid reads every model it writes.
#include "ctid/io/json.h"
#include "ctid/io/model_json.h"
#include "harness.h"

namespace {

template <class Read>
void read_write_read(const nlohmann::json& document, Read read) {
  ctid::fuzz::refuse_or_use(document, [&](const nlohmann::json& value) {
    const auto model = read(value);
    ctid::fuzz::must_read_back([&] { (void)read(ctid::io::to_json(model)); });
  });
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  return ctid::fuzz::refuse_or_read(data, size, [](std::string_view text) {
    const nlohmann::json document = ctid::io::parse_json(text, "fuzz.json");
    read_write_read(document, [](const nlohmann::json& v) {
      return ctid::io::continuous_model_from_json(v, "fuzz.json");
    });
    read_write_read(document, [](const nlohmann::json& v) {
      return ctid::io::mimo_additive_model_from_json(v, "fuzz.json");
    });
    read_write_read(document, [](const nlohmann::json& v) {
      return ctid::io::discrete_transfer_function_from_json(v, "fuzz.json");
    });
    read_write_read(document, [](const nlohmann::json& v) {
      return ctid::io::delayed_feedback_loop_from_json(v, "fuzz.json");
    });
  });
}
