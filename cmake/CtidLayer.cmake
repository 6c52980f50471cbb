# ctid_add_layer(<name> DEPENDS <targets>...)
# Creates the static library ctid_<name> from src/<name>/*.cc with public headers in
# include/ctid/<name>/, the alias ctid::<name>, and records it in CTID_LAYERS for the
# umbrella target and for installation.
set(CTID_LAYERS "" CACHE INTERNAL "")
function(ctid_add_layer name)
  cmake_parse_arguments(ARG "" "" "DEPENDS" ${ARGN})
  file(GLOB sources CONFIGURE_DEPENDS "${PROJECT_SOURCE_DIR}/src/${name}/*.cc")
  if(NOT sources)
    message(FATAL_ERROR "ctid layer '${name}' has no sources in src/${name}/")
  endif()
  set(target ctid_${name})
  add_library(${target} STATIC ${sources})
  add_library(ctid::${name} ALIAS ${target})
  target_include_directories(${target}
    PUBLIC $<BUILD_INTERFACE:${PROJECT_SOURCE_DIR}/include> $<INSTALL_INTERFACE:include>
    PRIVATE ${PROJECT_SOURCE_DIR}/src)
  target_link_libraries(${target} PUBLIC ${ARG_DEPENDS} PRIVATE $<BUILD_INTERFACE:ctid_compile_options>)
  set_target_properties(${target} PROPERTIES EXPORT_NAME ${name})
  set(CTID_LAYERS ${CTID_LAYERS} ${target} CACHE INTERNAL "")
endfunction()

# ctid_add_layer_tests(<layer> [LIBS <targets>...])
# One GoogleTest executable per layer from tests/<layer>/*_test.cc.
function(ctid_add_layer_tests name)
  cmake_parse_arguments(ARG "" "" "LIBS" ${ARGN})
  file(GLOB sources CONFIGURE_DEPENDS "${PROJECT_SOURCE_DIR}/tests/${name}/*_test.cc")
  if(NOT sources)
    return()
  endif()
  set(target ctid_${name}_tests)
  add_executable(${target} ${sources})
  target_include_directories(${target} PRIVATE ${PROJECT_SOURCE_DIR}/src ${PROJECT_SOURCE_DIR}/tests)
  target_link_libraries(${target} PRIVATE ctid::ctid ${ARG_LIBS} GTest::gtest GTest::gmock GTest::gtest_main
    ctid_compile_options)
  target_compile_definitions(${target} PRIVATE
    CTID_SOURCE_DIR="${PROJECT_SOURCE_DIR}" CTID_SHARED_DIR="${PROJECT_SOURCE_DIR}/../shared")
  gtest_discover_tests(${target} DISCOVERY_TIMEOUT 60 PROPERTIES LABELS ${name})
endfunction()
