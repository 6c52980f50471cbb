# Compiler flags shared by every ctid target: warnings (errors by default) and sanitizers.
# -Wnull-dereference is left out: GCC 12 at -O2/-O3 reports it inside Eigen and
# std::complex for dynamic-size vectors that may be empty (false positives, not our code).
add_library(ctid_compile_options INTERFACE)
target_compile_options(ctid_compile_options INTERFACE
  -Wall -Wextra -Wpedantic -Wshadow -Wnon-virtual-dtor -Wold-style-cast -Wcast-align
  -Wunused -Woverloaded-virtual -Wdouble-promotion -Wformat=2
  -Wimplicit-fallthrough
  # GCC 12 reports false -Wrestrict positives inside std::string concatenation at -O3.
  $<$<CXX_COMPILER_ID:GNU>:-Wno-restrict>
  $<$<BOOL:${CTID_WERROR}>:-Werror>)

# Sanitizers apply to the whole build (libraries, tests, CLI, benchmarks) rather than
# through ctid_compile_options: every object that ends up in one executable must agree,
# or a target that forgets the flag fails to link against instrumented static libraries.
if(CTID_SANITIZE)
  add_compile_options(-fsanitize=address,undefined -fno-omit-frame-pointer
    -fno-sanitize-recover=all)
  add_link_options(-fsanitize=address,undefined)
endif()

# Rebuilds are much faster with ccache; use it when the machine has it.
find_program(CTID_CCACHE ccache)
if(CTID_CCACHE AND NOT CMAKE_CXX_COMPILER_LAUNCHER)
  set(CMAKE_CXX_COMPILER_LAUNCHER ${CTID_CCACHE})
endif()
