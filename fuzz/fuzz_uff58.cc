// libFuzzer harness of the universal-file-format 58 reader (io/uff58.h). An FRF matrix that
// was read must be written (format_uff58) and read back.
#include "ctid/io/uff58.h"
#include "harness.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  return ctid::fuzz::refuse_or_read(data, size, [](std::string_view text) {
    const ctid::MimoFrf frf = ctid::io::parse_uff58(text, "fuzz.uff");
    ctid::fuzz::must_read_back(
        [&] { (void)ctid::io::parse_uff58(ctid::io::format_uff58(frf), "again.uff"); });
  });
}
