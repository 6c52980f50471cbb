// libFuzzer harness of the excitation-spec reader (io/excitation_spec.h): a spec that was
// read must be written and read back.
#include "ctid/io/excitation_spec.h"
#include "ctid/io/json.h"
#include "harness.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  return ctid::fuzz::refuse_or_read(data, size, [](std::string_view text) {
    const ctid::io::ExcitationSpec spec =
        ctid::io::excitation_spec_from_json(ctid::io::parse_json(text, "fuzz.json"), "fuzz.json");
    ctid::fuzz::must_read_back(
        [&] { (void)ctid::io::excitation_spec_from_json(ctid::io::to_json(spec), "again.json"); });
  });
}
