# Test helpers. Every test is a GoogleTest executable (or a driver run) registered with CTest.
#   perinox_add_gtest(NAME <name> SOURCES <files...> LIBS <libs...> [NP <n>] [LABELS <labels...>])
# With NP the test runs under mpiexec with n ranks; running as root and oversubscribing the
# 2-core machine are allowed here, in the registration, so nobody has to set them by hand.
find_package(GTest REQUIRED)

set(PERINOX_MPIEXEC_FLAGS --oversubscribe)
set(PERINOX_TEST_ENV "OMPI_ALLOW_RUN_AS_ROOT=1;OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1;OMPI_MCA_rmaps_base_oversubscribe=1")

function(perinox_mpi_command out np)
  set(${out} ${MPIEXEC_EXECUTABLE} ${MPIEXEC_NUMPROC_FLAG} ${np} ${PERINOX_MPIEXEC_FLAGS} PARENT_SCOPE)
endfunction()

function(perinox_add_gtest)
  cmake_parse_arguments(T "OWN_MAIN" "NAME;NP;TIMEOUT" "SOURCES;LIBS;LABELS;NPS" ${ARGN})
  add_executable(${T_NAME} ${T_SOURCES})
  if(T_OWN_MAIN)
    target_link_libraries(${T_NAME} PRIVATE ${T_LIBS} GTest::gtest)
  else()
    target_link_libraries(${T_NAME} PRIVATE ${T_LIBS} GTest::gtest GTest::gtest_main)
  endif()
  if(NOT T_NPS)
    if(T_NP)
      set(T_NPS ${T_NP})
    else()
      set(T_NPS 1)
    endif()
  endif()
  if(NOT T_TIMEOUT)
    set(T_TIMEOUT 600)
  endif()
  foreach(np ${T_NPS})
    perinox_mpi_command(cmd ${np})
    if(np EQUAL 1)
      set(tname ${T_NAME})
    else()
      set(tname ${T_NAME}_np${np})
    endif()
    add_test(NAME ${tname} COMMAND ${cmd} $<TARGET_FILE:${T_NAME}>)
    set(labels ${T_LABELS})
    if(np GREATER 1)
      list(APPEND labels mpi)
    endif()
    set_tests_properties(${tname} PROPERTIES ENVIRONMENT "${PERINOX_TEST_ENV}"
      LABELS "${labels}" PROCESSORS ${np} TIMEOUT ${T_TIMEOUT})
    perinox_unit_test(${tname})
  endforeach()
endfunction()

# Labels say what a test is (docs/testing.md). `unit` is kept only by the tests named here: the
# gtest programs of the packages (perinox_add_gtest names its own) and tools' tests that run no
# perinox driver and need no test that does. perinox_finalize_labels() runs last and takes `unit`
# from every other test; one left without a label then gets `driver` (it runs the driver, or
# compares what driver runs wrote).
function(perinox_unit_test)
  set_property(GLOBAL APPEND PROPERTY PERINOX_UNIT_TESTS ${ARGN})
endfunction()

# `quick`: a subset that exercises every package in a few minutes (docs/testing.md lists it and
# its time), for a developer's loop; the whole suite stays the README's test command and CI's.
function(perinox_quick_tests)
  set_property(GLOBAL APPEND PROPERTY PERINOX_QUICK_TESTS ${ARGN})
endfunction()

# Called at the end of each CMakeLists.txt that adds tests (get_test_property sees only the current
# directory's tests in this CMake).
function(perinox_finalize_labels)
  get_property(unit GLOBAL PROPERTY PERINOX_UNIT_TESTS)
  get_property(quick GLOBAL PROPERTY PERINOX_QUICK_TESTS)
  get_property(tests DIRECTORY PROPERTY TESTS)
  foreach(t ${tests})
    get_test_property(${t} LABELS labels)
    if(NOT labels)
      set(labels "")
    endif()
    if(NOT t IN_LIST unit)
      list(REMOVE_ITEM labels unit)
      if(NOT labels)
        set(labels driver)
      endif()
    elseif(NOT "unit" IN_LIST labels)
      list(APPEND labels unit)
    endif()
    if(t IN_LIST quick)
      list(APPEND labels quick)
    endif()
    set_tests_properties(${t} PROPERTIES LABELS "${labels}")
  endforeach()
  set_property(GLOBAL APPEND PROPERTY PERINOX_LABELLED_TESTS ${tests})
endfunction()

# At the top level, after every directory: each name given to perinox_quick_tests is a test.
function(perinox_check_quick_tests)
  get_property(quick GLOBAL PROPERTY PERINOX_QUICK_TESTS)
  get_property(all GLOBAL PROPERTY PERINOX_LABELLED_TESTS)
  foreach(t ${quick})
    if(NOT t IN_LIST all)
      message(FATAL_ERROR "perinox_quick_tests names '${t}', which is no test")
    endif()
  endforeach()
endfunction()
