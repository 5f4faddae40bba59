# Installs a normalflow build into a scratch prefix, configures and builds tests/consumer/project against it with
# find_package(normalflow), and runs the result; then the same main.cpp with pkg-config alone.
#   BUILD_DIR       the build to install, or
#   NORMALFLOW_SRC + CONFIGURE_ARGS ("|"-separated): configure and build normalflow's libraries that way first
#                   (a static build, a build with every optional adapter off)
#   SOURCE_DIR      tests/consumer/project;  WORK_DIR  scratch;  GENERATOR
file(REMOVE_RECURSE ${WORK_DIR})
function(run)
  execute_process(COMMAND ${ARGN} RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "consumer: `${ARGN}` failed (${rc}):\n${out}\n${err}")
  endif()
  set(last_output "${out}" PARENT_SCOPE)
endfunction()
if(DEFINED CONFIGURE_ARGS)
  string(REPLACE "|" ";" args "${CONFIGURE_ARGS}")
  set(BUILD_DIR ${WORK_DIR}/normalflow)
  # Release, as a user builds it, but -O0: these builds test the package (exports, private dependencies,
  # pkg-config), not the code's speed, and the optimiser is most of their compile time.
  run(${CMAKE_COMMAND} -S ${NORMALFLOW_SRC} -B ${BUILD_DIR} -G ${GENERATOR} -DCMAKE_BUILD_TYPE=Release
      "-DCMAKE_CXX_FLAGS_RELEASE=-O0 -DNDEBUG" "-DCMAKE_C_FLAGS_RELEASE=-O0 -DNDEBUG" -DNORMALFLOW_BUILD_APPS=OFF -DNORMALFLOW_BUILD_TESTS=OFF -DNORMALFLOW_BUILD_BENCHMARKS=OFF
      -DNORMALFLOW_BUILD_PYTHON=OFF ${args})
  run(${CMAKE_COMMAND} --build ${BUILD_DIR})
endif()
set(prefix ${WORK_DIR}/prefix)
run(${CMAKE_COMMAND} --install ${BUILD_DIR} --prefix ${prefix})
run(${CMAKE_COMMAND} -S ${SOURCE_DIR} -B ${WORK_DIR}/build -G ${GENERATOR}
    -DCMAKE_BUILD_TYPE=Release -DCMAKE_PREFIX_PATH=${prefix})
run(${CMAKE_COMMAND} --build ${WORK_DIR}/build)
run(${WORK_DIR}/build/consumer ${WORK_DIR}/tet.ply)
if(NOT last_output MATCHES "consumer ok")
  message(FATAL_ERROR "consumer: unexpected output: ${last_output}")
endif()
message(STATUS "find_package: ${last_output}")

# pkg-config: the installed normalflow.pc alone (relocatable: the scratch prefix), --static for a static build
find_program(PKG_CONFIG pkg-config)
if(PKG_CONFIG)
  file(GLOB pc ${prefix}/lib*/pkgconfig/normalflow.pc ${prefix}/lib/*/pkgconfig/normalflow.pc)
  if(NOT pc)
    message(FATAL_ERROR "consumer: no normalflow.pc installed under ${prefix}")
  endif()
  get_filename_component(pcdir ${pc} DIRECTORY)
  get_filename_component(libdir ${pcdir} DIRECTORY)
  set(ENV{PKG_CONFIG_PATH} ${pcdir})
  set(static "")
  if(EXISTS ${libdir}/libnormalflow_core.a)
    set(static --static)
  endif()
  run(${PKG_CONFIG} --cflags --libs ${static} normalflow)
  string(STRIP "${last_output}" flags)
  separate_arguments(flags UNIX_COMMAND "${flags}")
  run(c++ ${SOURCE_DIR}/main.cpp -o ${WORK_DIR}/consumer_pc ${flags} -Wl,-rpath,${libdir})
  run(${WORK_DIR}/consumer_pc ${WORK_DIR}/tet_pc.ply)
  if(NOT last_output MATCHES "consumer ok")
    message(FATAL_ERROR "consumer (pkg-config): unexpected output: ${last_output}")
  endif()
  message(STATUS "pkg-config: ${last_output}")
endif()
