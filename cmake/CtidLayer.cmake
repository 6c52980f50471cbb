# ctid_add_layer(<name> DEPENDS <targets>...)
# Creates the library ctid_<name> from src/<name>/*.cc with public headers in
# include/ctid/<name>/, the alias ctid::<name>, and records it in CTID_LAYERS for the
# umbrella target and for installation. A layer with no sources yet becomes an INTERFACE
# library (headers + dependencies only), so the tree configures and builds at every stage.
set(CTID_LAYERS "" CACHE INTERNAL "")
function(ctid_add_layer name)
  cmake_parse_arguments(ARG "" "" "DEPENDS" ${ARGN})
  file(GLOB sources CONFIGURE_DEPENDS "${PROJECT_SOURCE_DIR}/src/${name}/*.cc")
  set(target ctid_${name})
  if(sources)
    add_library(${target} STATIC ${sources})
    target_include_directories(${target}
      PUBLIC $<BUILD_INTERFACE:${PROJECT_SOURCE_DIR}/include> $<INSTALL_INTERFACE:include>
      PRIVATE ${PROJECT_SOURCE_DIR}/src)
    # Consumers of the installed package need C++20 too (our headers use it).
    target_compile_features(${target} PUBLIC cxx_std_20)
    target_link_libraries(${target} PUBLIC ${ARG_DEPENDS}
      PRIVATE $<BUILD_INTERFACE:ctid_compile_options>)
  else()
    message(STATUS "ctid layer '${name}' has no sources yet: header-only INTERFACE library")
    add_library(${target} INTERFACE)
    target_include_directories(${target}
      INTERFACE $<BUILD_INTERFACE:${PROJECT_SOURCE_DIR}/include> $<INSTALL_INTERFACE:include>)
    target_compile_features(${target} INTERFACE cxx_std_20)
    target_link_libraries(${target} INTERFACE ${ARG_DEPENDS})
  endif()
  add_library(ctid::${name} ALIAS ${target})
  set_target_properties(${target} PROPERTIES EXPORT_NAME ${name})
  set(CTID_LAYERS ${CTID_LAYERS} ${target} CACHE INTERNAL "")
endfunction()

# ctid_add_layer_tests(<layer> [LIBS <targets>...])
# One GoogleTest executable per layer from tests/<layer>/*_test.cc, its tests labelled with
# the layer's name (ctest -L core runs one layer; ctest -LE install all but the install test).
# One label only: gtest_discover_tests flattens a list-valued LABELS property.
function(ctid_add_layer_tests name)
  cmake_parse_arguments(ARG "" "" "LIBS" ${ARGN})
  file(GLOB sources CONFIGURE_DEPENDS "${PROJECT_SOURCE_DIR}/tests/${name}/*_test.cc")
  if(NOT sources)
    return()
  endif()
  set(target ctid_${name}_tests)
  add_executable(${target} ${sources})
  target_include_directories(${target} PRIVATE ${PROJECT_SOURCE_DIR}/src ${PROJECT_SOURCE_DIR}/tests)
  target_link_libraries(${target} PRIVATE ctid::${name} ${ARG_LIBS} GTest::gtest GTest::gmock GTest::gtest_main
    ctid_compile_options)
  target_compile_definitions(${target} PRIVATE
    CTID_SOURCE_DIR="${PROJECT_SOURCE_DIR}" CTID_SHARED_DIR="${PROJECT_SOURCE_DIR}/../shared")
  gtest_discover_tests(${target} DISCOVERY_TIMEOUT 60 PROPERTIES LABELS ${name})
endfunction()
