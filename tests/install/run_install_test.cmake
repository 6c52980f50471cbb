# Installs the built ctid into a fresh prefix, then configures, builds and runs the consumer
# project in tests/install/consumer against that prefix only.
# cmake -DBUILD_DIR=... -DCONSUMER_DIR=... -DWORK_DIR=... -DGENERATOR=... -DCXX_COMPILER=...
#       -DBUILD_TYPE=... -P run_install_test.cmake
foreach(var BUILD_DIR CONSUMER_DIR WORK_DIR GENERATOR CXX_COMPILER BUILD_TYPE)
  if(NOT DEFINED ${var})
    message(FATAL_ERROR "run_install_test.cmake: ${var} is not set")
  endif()
endforeach()

function(run what)
  execute_process(COMMAND ${ARGN} RESULT_VARIABLE rc)
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "install test: ${what} failed (${rc})")
  endif()
endfunction()

set(prefix ${WORK_DIR}/prefix)
file(REMOVE_RECURSE ${WORK_DIR})
run("cmake --install" ${CMAKE_COMMAND} --install ${BUILD_DIR} --prefix ${prefix})
run("configuring the consumer" ${CMAKE_COMMAND} -S ${CONSUMER_DIR} -B ${WORK_DIR}/build
  -G ${GENERATOR} -DCMAKE_CXX_COMPILER=${CXX_COMPILER} -DCMAKE_BUILD_TYPE=${BUILD_TYPE}
  -DCMAKE_PREFIX_PATH=${prefix} -DEXPECTED_PREFIX=${prefix}
  -DCMAKE_FIND_USE_PACKAGE_REGISTRY=OFF)
run("building the consumer" ${CMAKE_COMMAND} --build ${WORK_DIR}/build)
run("running the consumer" ${WORK_DIR}/build/consumer)
message(STATUS "install test: find_package(ctid) consumer built and ran against ${prefix}")

# With the Python package built, the installed tree imports under /usr/bin/python3 and the
# installed CLI finds it for --plot (it looks in <prefix>/lib/ctid/python).
if(EXISTS ${BUILD_DIR}/python/ctid/plot.py AND EXISTS /usr/bin/python3)
  execute_process(
    COMMAND ${CMAKE_COMMAND} -E env PYTHONPATH=${prefix}/lib/ctid/python
            /usr/bin/python3 -c "import ctid, ctid.plot; assert ctid.__file__.startswith('${prefix}'); print(ctid.fit_percent([1.0, 2.0], [1.0, 2.0]))"
    RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
  if(NOT rc EQUAL 0 OR NOT out MATCHES "^100")
    message(FATAL_ERROR "install test: the installed Python package does not import: ${out}${err}")
  endif()
  if(EXISTS ${prefix}/bin/ctid)
    file(WRITE ${WORK_DIR}/d.csv "t,u,y\n")
    foreach(k RANGE 0 99)
      math(EXPR u "(${k} * 37) % 11 - 5")
      file(APPEND ${WORK_DIR}/d.csv "${k},${u},${u}\n")
    endforeach()
    execute_process(
      COMMAND ${CMAKE_COMMAND} -E env --unset=CTID_PYTHONPATH
              ${prefix}/bin/ctid frf ${WORK_DIR}/d.csv --plot ${WORK_DIR}/fig -q
      RESULT_VARIABLE rc ERROR_VARIABLE err)
    if(NOT rc EQUAL 0 OR NOT EXISTS ${WORK_DIR}/fig/frf.png)
      message(FATAL_ERROR "install test: the installed ctid could not plot: ${err}")
    endif()
  endif()
  message(STATUS "install test: the installed Python package imports and ctid --plot uses it")
endif()
