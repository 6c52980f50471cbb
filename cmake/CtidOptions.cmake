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
# AddressSanitizer and UndefinedBehaviorSanitizer, less five UBSan checks that cost the most
# to compile and find nothing here that the rest do not (docs/decisions/0032): null and
# object-size (AddressSanitizer reports the same accesses), alignment (Eigen aligns its own
# storage and no reader casts bytes to wider types), vptr (almost no polymorphic classes) and
# pointer-overflow. Sanitized executables are not position-independent: a PIE of them carries
# some 3 million dynamic relocations (the sanitizers' per-check data), which every process start
# applies, and the tests start thousands of processes (each gtest case, each ctid run).
if(CTID_SANITIZE)
  add_compile_options(-fsanitize=address,undefined
    -fno-sanitize=null,object-size,alignment,vptr,pointer-overflow -fno-omit-frame-pointer
    -fno-sanitize-recover=all -fno-pie)
  add_link_options(-fsanitize=address,undefined -no-pie)
  set(CMAKE_POSITION_INDEPENDENT_CODE OFF)
endif()

# Rebuilds are much faster with ccache; use it when the machine has it.
find_program(CTID_CCACHE ccache)
if(CTID_CCACHE AND NOT CMAKE_CXX_COMPILER_LAUNCHER)
  set(CMAKE_CXX_COMPILER_LAUNCHER ${CTID_CCACHE})
endif()

# Glue: the command line's parsing and printing and the Python bindings' conversions do no
# numerical work of their own (every estimate is computed in the library, compiled at -O3), so
# in Release they are compiled at -O1, which takes about 40 % less compile time than -O3 on
# these files and gives the same bits (no -ffast-math, no FMA contraction on x86-64's baseline;
# the behaviour snapshot and the Python bit-equality tests check it). Decision 0048.
function(ctid_compile_as_glue target)
  target_compile_options(${target} PRIVATE $<$<CONFIG:Release>:-O1>)
endfunction()
