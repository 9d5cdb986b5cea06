# tools/peridigm_to_scene.py against hostile, malformed and impossible Peridigm decks
# (tests/peridigm/test_peridigm_converter.py): its Value grammar (Python code, powers, functions,
# a 100 000-character expression refused; accepted ones give the hand-worked coefficients), every
# kind of malformed deck, impossible constants and load steps, any two elastic constants against
# the closed forms, and a seeded mutation loop over Peridigm's tensile deck. Every deck is
# converted (exit 0) or refused with one sentence and exit code 2, no traceback, nothing written.
# Python only: it needs no build. Included by tests/CMakeLists.txt.

# Peridigm's tensile deck is the mutation loop's base when the repository's copy is there
# (exodus_tests.cmake's PERINOX_TENSILE_DIR); otherwise the test writes a deck of the same shape.
if(DEFINED PERINOX_TENSILE_DIR)
  set(pd_converter_tensile ${PERINOX_TENSILE_DIR})
else()
  get_filename_component(pd_converter_tensile ${PROJECT_SOURCE_DIR}/validation/benchmarks/peridigm_tensile ABSOLUTE)
endif()
set(pd_converter_args --tool ${PROJECT_SOURCE_DIR}/tools/peridigm_to_scene.py --seed 2024)
if(EXISTS ${pd_converter_tensile}/tensile_test.yaml)
  list(APPEND pd_converter_args --tensile-deck ${pd_converter_tensile}/tensile_test.yaml)
endif()
add_test(NAME tools_peridigm_converter
  COMMAND ${Python3_EXECUTABLE} ${CMAKE_CURRENT_SOURCE_DIR}/peridigm/test_peridigm_converter.py ${pd_converter_args})
set_tests_properties(tools_peridigm_converter PROPERTIES LABELS "unit;badinput" TIMEOUT 300)
perinox_unit_test(tools_peridigm_converter)
