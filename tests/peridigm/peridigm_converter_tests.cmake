# The library's reader of Peridigm decks (perinox convert) against hostile, malformed and
# impossible decks (tests/peridigm/test_peridigm_converter.py): the Value grammar (Python code,
# powers, functions, a 100 000-character expression refused; accepted ones give the hand-worked
# coefficients), every kind of malformed deck and what Teuchos' YAML reader cannot read, impossible
# constants and load steps, any two elastic constants against the closed forms, and a seeded
# mutation loop over Peridigm's tensile deck. Every deck is converted (exit 0) or refused with one
# sentence and exit code 2, within 10 s, nothing written. Included by tests/CMakeLists.txt.

# Peridigm's tensile deck is the mutation loop's base when the repository's copy is there
# (exodus_tests.cmake's PERINOX_TENSILE_DIR); otherwise the test writes a deck of the same shape.
if(DEFINED PERINOX_TENSILE_DIR)
  set(pd_converter_tensile ${PERINOX_TENSILE_DIR})
else()
  get_filename_component(pd_converter_tensile ${PROJECT_SOURCE_DIR}/validation/benchmarks/peridigm_tensile ABSOLUTE)
endif()
set(pd_converter_args --perinox $<TARGET_FILE:perinox> --seed 2024 --cases 200)
if(EXISTS ${pd_converter_tensile}/tensile_test.yaml)
  list(APPEND pd_converter_args --tensile-deck ${pd_converter_tensile}/tensile_test.yaml)
endif()
add_test(NAME peridigm_deck_hostile
  COMMAND ${Python3_EXECUTABLE} ${CMAKE_CURRENT_SOURCE_DIR}/peridigm/test_peridigm_converter.py ${pd_converter_args})
set_tests_properties(peridigm_deck_hostile PROPERTIES ENVIRONMENT "${PERINOX_TEST_ENV}" LABELS badinput TIMEOUT 600 PROCESSORS 2)
