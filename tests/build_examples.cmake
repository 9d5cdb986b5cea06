# Configures and builds examples/ as a separate project against an installed perinox (CTest
# examples_build):  cmake -DSOURCE=<examples> -DBUILD=<dir> -DPREFIX=<install prefix> -P build_examples.cmake
# The build folder is made afresh, and perinox must be found in PREFIX, through find_package only.
file(REMOVE_RECURSE ${BUILD})
execute_process(COMMAND ${CMAKE_COMMAND} -S ${SOURCE} -B ${BUILD} -DCMAKE_BUILD_TYPE=Release
  -DCMAKE_PREFIX_PATH=${PREFIX} -DCMAKE_FIND_USE_PACKAGE_REGISTRY=OFF RESULT_VARIABLE rc)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "configuring ${SOURCE} against ${PREFIX} failed")
endif()
file(STRINGS ${BUILD}/CMakeCache.txt found REGEX "^perinox_DIR:")
get_filename_component(prefix_real ${PREFIX} REALPATH)
string(REGEX REPLACE "^perinox_DIR:[A-Z]*=" "" found "${found}")
get_filename_component(found_real "${found}" REALPATH)
string(FIND "${found_real}" "${prefix_real}/" at)
if(NOT at EQUAL 0)
  message(FATAL_ERROR "the examples found perinox in '${found}', not in ${PREFIX}")
endif()
execute_process(COMMAND ${CMAKE_COMMAND} --build ${BUILD} -j2 RESULT_VARIABLE rc)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "building the examples failed")
endif()
