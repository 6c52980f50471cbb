// libFuzzer harness of the .npy reader (io/npy.h) and of the table it becomes.
#include "ctid/io/npy.h"
#include "harness.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  return ctid::fuzz::refuse_or_read(data, size, [](std::string_view bytes) {
    const ctid::io::NpyArray array = ctid::io::parse_npy(bytes, "fuzz.npy");
    const ctid::io::CsvTable table = ctid::io::npy_table(array, "fuzz.npy");
    // The direct reader (what read_table uses) gives the same table.
    const ctid::io::CsvTable direct = ctid::io::parse_npy_table(bytes, "fuzz.npy");
    if (direct.names != table.names || direct.columns != table.columns) {
      ctid::fuzz::finding("parse_npy_table differs from npy_table(parse_npy)");
    }
  });
}
