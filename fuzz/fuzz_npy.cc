// libFuzzer harness of the .npy reader (io/npy.h) and of the table it becomes.
#include "ctid/io/npy.h"
#include "harness.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  return ctid::fuzz::refuse_or_read(data, size, [](std::string_view bytes) {
    const ctid::io::NpyArray array = ctid::io::parse_npy(bytes, "fuzz.npy");
    (void)ctid::io::npy_table(array, "fuzz.npy");
  });
}
