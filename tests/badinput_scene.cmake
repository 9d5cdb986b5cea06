# Scene input validation (packages/io/src/Scene.cpp, SceneText.cpp): each bad input gets one
# sentence naming the file or --set argument and the key, exit code 2, nothing written.
# Included by tests/CMakeLists.txt after perinox_bad_input is defined.

# Scenes kept as a recipe rather than as files (NUL bytes, Latin-1, a byte-order mark, ...):
# tests/bad_input/make_scenes.py writes them at configure time.
set(GEN ${CMAKE_CURRENT_BINARY_DIR}/bad_input_generated)
execute_process(COMMAND ${Python3_EXECUTABLE} ${CMAKE_CURRENT_SOURCE_DIR}/bad_input/make_scenes.py
  ${CMAKE_CURRENT_SOURCE_DIR} ${GEN} RESULT_VARIABLE gen_result)
if(NOT gen_result EQUAL 0)
  message(FATAL_ERROR "tests/bad_input/make_scenes.py failed: ${gen_result}")
endif()
set_property(DIRECTORY APPEND PROPERTY CMAKE_CONFIGURE_DEPENDS
  ${CMAKE_CURRENT_SOURCE_DIR}/bad_input/make_scenes.py ${CMAKE_CURRENT_SOURCE_DIR}/bad_input/tiny.xml)

# perinox_bad_sets(SCENE NAME MESSAGE SET [NAME MESSAGE SET]...): for each triple, a bad-input
# test badinput_NAME running SCENE with --set SET and expecting MESSAGE.
function(perinox_bad_sets scene)
  set(rest ${ARGN})
  while(rest)
    list(POP_FRONT rest name message set)
    perinox_bad_input(${name} ${scene} "${message}" --set "${set}")
  endwhile()
endfunction()

set(TINY ${BAD}/tiny.xml)
set(XML ${PROJECT_SOURCE_DIR}/xml)
set(NOT_FINITE "is not a finite number")
set(INT_RANGE "is not an integer from -2147483648 to 2147483647")
set(SIDES "must be xmin, xmax, ymin, ymax, zmin or zmax")
set(CONFLICT "prescribe different values")
set(WORK_BOUND "must be from 1 to 1000000, not")

# 1. NaN, infinity and overflow, in the XML and in --set.
foreach(case nan_load inf_load overflow_array nan_reference_stretch)
  perinox_bad_input(xml_${case} ${GEN}/xml_${case}.xml "${NOT_FINITE}")
endforeach()
perinox_bad_sets(${TINY}
  set_nan_load "${NOT_FINITE}" "Loads/tip load/Value={nan, nan}"
  set_inf_load "${NOT_FINITE}" "Loads/tip load/Value={inf, 0}"
  set_nan_bc_value "${NOT_FINITE}" "Boundary Conditions/pull/Value=nan"
  set_inf_bc_value "${NOT_FINITE}" "Boundary Conditions/pull/Value=-inf"
  set_inf_bc_gradient "${NOT_FINITE}" "Boundary Conditions/pull/Gradient={inf, 0}"
  set_nan_point "${NOT_FINITE}" "Regions/tip/Point={nan, 0.15}"
  set_nan_lower_corner "${NOT_FINITE}" "Discretization/Lower Corner={nan, 0}"
  set_overflow_array "${NOT_FINITE}" "Discretization/Lower Corner={-1e999, 0}"
  set_nan_reference_stretch "${NOT_FINITE}" "Reference/Stretch=nan")

# 2. Array lengths: exactly Dimension entries (none or Dimension for Particles and a condition's
# Gradient; Dimension x Dimension for the reference Gradient; 3 for the rotation Axis).
perinox_bad_sets(${TINY}
  length_lower_corner "'Discretization/Lower Corner' has 1 entry but needs 2" "Discretization/Lower Corner={0}"
  length_load_value "'Loads/tip load/Value' has 1 entry but needs 2" "Loads/tip load/Value={1.0}"
  length_nearest_point "'Regions/tip/Point' has 1 entry but needs 2" "Regions/tip/Point={0.5}"
  length_particles "'Discretization/Particles' has 3 entries but needs 0 or 2" "Discretization/Particles={6, 3, 2}")
perinox_bad_sets(${XML}/tension_block.xml
  length_box_2d "'Regions/pin/Lower' has 1 entry but needs 2" "Regions/pin/Lower={-1.0}"
  length_box_upper_2d "'Regions/pin/Upper' has 3 entries but needs 2" "Regions/pin/Upper={0.0, 0.03, 0.0}"
  length_reference_center "'Reference/Center' has 1 entry but needs 2" "Reference/Center={0.0}")
perinox_bad_sets(${XML}/brick3d.xml
  length_box_3d "'Regions/face x0/Lower' has 2 entries but needs 3" "Regions/face x0/Lower={-0.5, -0.5}"
  length_point_3d "'Regions/bottom centre/Point' has 2 entries but needs 3" "Regions/bottom centre/Point={40.0, 40.0}")
perinox_bad_sets(${XML}/bar1d_variable_modulus.xml
  length_point_1d_empty "'Regions/quarter/Point' has 0 entries but needs 1" "Regions/quarter/Point={}")
perinox_bad_sets(${XML}/plate_square_opening.xml
  length_hole_half_widths "'Discretization/Holes/opening/Half Widths' has 0 entries but needs 2" "Discretization/Holes/opening/Half Widths={}")
perinox_bad_sets(${XML}/hard/rotated_cantilever.xml
  length_rotation_axis "'Superposed Rotation/Axis' has 2 entries but needs 3" "Superposed Rotation/Axis={0, 1}")

# 3. Integers out of range are refused, never wrapped or truncated; arrays need braces.
perinox_bad_sets(${TINY}
  int_load_steps_wrap "${INT_RANGE}" "Solver/Load Steps=4294967297"
  int_load_steps_negative_wrap "${INT_RANGE}" "Solver/Load Steps=-4294967295"
  int_jitter_seed "${INT_RANGE}" "Discretization/Jitter Seed=99999999999"
  int_stress_point_seed "${INT_RANGE}" "Model/Stress Point Seed=99999999999"
  int_particles_fraction "entry 1, '20.7', is not an integer" "Discretization/Particles={20.7,10}"
  array_without_braces "'10,5' is not an array like {20, 10}" "Discretization/Particles=10,5")
perinox_bad_input(mumps_refactor_negative ${GEN}/mumps_refactor_negative.xml "MUMPS: 'Refactor Above Krylov Iterations' must be at least 0")
perinox_bad_input(mumps_excess_negative ${GEN}/mumps_excess_negative.xml "MUMPS: 'Refactor Above Excess Applications' must be at least 0")
perinox_bad_input(mumps_precision_unknown ${GEN}/mumps_precision_unknown.xml "MUMPS/Factor Precision' = 'Half' is not an allowed value")
perinox_bad_input(mumps_within_solve_not_flexible ${GEN}/mumps_within_solve_not_flexible.xml
  "it needs Belos 'Block GMRES' with 'Flexible Gmres' = true")
perinox_bad_input(forcing_term_bogus ${GEN}/forcing_term_bogus.xml "the linear solver preset's 'Forcing Term' must be Constant or Eisenstat-Walker (got 'Bogus')")
perinox_bad_input(xml_int_overflow ${GEN}/xml_int_overflow.xml "'Solver/Load Steps' = '4294967297' ${INT_RANGE}")

# 4. Contradicting Dirichlet conditions on one DOF, named both (the same value twice is allowed:
# xml/cantilever.xml's rollers and pin overlap with 0).
perinox_bad_input(bc_fixed_and_pulled ${TINY} "boundary conditions 'fix' and 'pull' ${CONFLICT} (0 and 0.0001)"
  --set "Boundary Conditions/pull/Region=left")
perinox_bad_input(bc_two_values ${TINY} "boundary conditions 'pull' and 'pull again' ${CONFLICT}"
  --set "Boundary Conditions/pull again/Region=right" --set "Boundary Conditions/pull again/Component=x"
  --set "Boundary Conditions/pull again/Value=0.0002")
perinox_bad_input(bc_all_and_x ${TINY} "boundary conditions 'pull' and 'hold' ${CONFLICT}"
  --set "Boundary Conditions/hold/Region=right")
perinox_bad_input(bc_overlapping_regions ${XML}/tension_block.xml "boundary conditions 'left rollers' and 'pin' ${CONFLICT}"
  --set "Boundary Conditions/left rollers/Component=all" --set "Boundary Conditions/pin/Value=0.01")

# 5. Enumerated values are matched exactly, with the allowed values in the message;
# 6. a long value is cut to 40 characters.
string(REPEAT "A" 300 long)
perinox_bad_sets(${TINY}
  enum_side_case "'Regions/left/Side' ${SIDES}, not 'XMIN' (did you mean 'xmin'?)" "Regions/left/Side=XMIN"
  enum_fictitious_sides_case "'Discretization/Fictitious Sides' has 'Xmin', but each entry ${SIDES}" "Discretization/Fictitious Sides={Xmin, xmax}"
  enum_model_typo "'Material/Model' must be Hencky or Small Strain, not 'small strain'" "Material/Model=small strain"
  enum_long_value "not 'AAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAA...'" "Regions/tip/Type=${long}"
  unknown_long_key "unknown key 'Solver/AAAAAAAAAAAA" "Solver/${long}=1")

# 7. The file itself: well-formed XML only, UTF-8 text, not empty; a byte-order mark is skipped.
foreach(case
    "xml_text_between_elements|xml_text_between_elements.xml:15: malformed scene XML: text 'stray text' inside <ParameterList>"
    "xml_element_in_parameter|<Parameter> inside the <Parameter> opened at line 7"
    "xml_nul_byte|xml_nul_byte.xml:5: the scene file contains a NUL byte"
    "xml_non_utf8_title|xml_non_utf8_title.xml:5: the scene file contains the byte 0xFF, which is not UTF-8"
    "xml_latin1_name|xml_latin1_name.xml:22: the scene file contains the byte 0xEA, which is not UTF-8"
    "xml_empty_file|the scene file is empty"
    "xml_whitespace_only|no <ParameterList> element"
    "xml_comment_only|no <ParameterList> element"
    "particle_file_nul|nul_particles.txt:10: contains a NUL byte")
  string(REPLACE "|" ";" case "${case}")
  list(GET case 0 name)
  list(GET case 1 message)
  perinox_bad_input(${name} ${GEN}/${name}.xml "${message}")
endforeach()
perinox_bad_input(scene_is_directory ${BAD} "is a directory, not a scene file")
perinox_bad_input(scene_dev_null /dev/null "/dev/null: the scene file is empty")
perinox_bad_sets(${PROJECT_SOURCE_DIR}/tests/scenes/tension_block_file.xml
  huge_horizon "'Discretization/Horizon' must be from the spacing to 50 x the spacing" "Discretization/Horizon=1e300")
perinox_bad_sets(${TINY}
  huge_horizon_factor "'Discretization/Horizon Factor' must be at most 50" "Discretization/Horizon Factor=1e300")
perinox_mpi_command(mpi_bom 1)
add_test(NAME badinput_bom_accepted COMMAND ${Python3_EXECUTABLE} ${PERINOX_CHECK} --out ${PERINOX_TEST_OUT}/badinput_bom_accepted
  --converged -- ${mpi_bom} $<TARGET_FILE:perinox> run ${GEN}/bom.xml --output ${PERINOX_TEST_OUT}/badinput_bom_accepted --quiet)
set_tests_properties(badinput_bom_accepted PROPERTIES ENVIRONMENT "${PERINOX_TEST_ENV};PERINOX_PLOT_SCRIPT=" LABELS "unit;badinput")

# 8. Presets are names (no paths), listed when unknown; an unreadable preset is one sentence.
perinox_bad_sets(${TINY}
  preset_parent_path "'../solvers/direct' is not a preset name (the files of xml/solvers, or custom: perinox schema --json lists them)" "Solver/Linear Solver Preset=../solvers/direct"
  preset_subdirectory "'solvers/direct' is not a preset name" "Solver/Linear Solver Preset=solvers/direct"
  preset_broken "cannot read the solver preset" "Solver/Linear Solver Preset=broken")
perinox_bad_input(preset_no_directory ${TINY} "there are no presets in")
set_property(TEST badinput_preset_broken APPEND PROPERTY ENVIRONMENT "PERINOX_XML_DIR=${GEN}/xml")
set_property(TEST badinput_preset_no_directory APPEND PROPERTY ENVIRONMENT "PERINOX_XML_DIR=${GEN}/no-such-directory")

# 9. Regions that need fictitious layers on a body without them; arc lengths out of order.
perinox_bad_sets(${XML}/hydrostatic.xml
  all_fictitious_without_layers "region 'ghost' selects fictitious particles, but the body has none" "Regions/ghost/Type=All Fictitious")
perinox_bad_sets(${XML}/hard/shallow_arch.xml
  arc_min_above_initial "'Solver/Arc Length/Min Arc Length' = 0.2 exceeds 'Initial Arc Length' = 0.1" "Solver/Arc Length/Min Arc Length=0.2"
  arc_max_steps_huge "'Solver/Arc Length/Max Steps' ${WORK_BOUND}" "Solver/Arc Length/Max Steps=2000000000")

# 10. Bounds on the work: load steps, total steps, cut-backs and particles (and 11 below).
perinox_bad_sets(${TINY}
  load_steps_huge "'Solver/Load Steps' ${WORK_BOUND} 107374182" "Solver/Load Steps=107374182"
  load_steps_overflow "'Solver/Load Steps' ${WORK_BOUND} 107374183" "Solver/Load Steps=107374183"
  max_total_steps_huge "'Solver/Max Total Steps' must be 0 (20 x Load Steps) or from" "Solver/Max Total Steps=2000000000"
  max_cutbacks_huge "'Solver/Max Cutbacks' must be from 0 to 60" "Solver/Max Cutbacks=1000"
  particles_too_many "at most 50000000 are allowed" "Discretization/Particles={20000, 10000}"
  # 11. Other impossible values.
  spacing_zero "needs Particles (counts per axis) or a positive Spacing" "Discretization/Particles={}"
  spacing_and_particles "gives both Particles and Spacing" "Discretization/Spacing=0.1"
  particles_negative "'Discretization/Particles' counts must be at least 1" "Discretization/Particles={-6, 3}"
  jitter_seed_negative "'Discretization/Jitter Seed' must be at least 0, not -1" "Discretization/Jitter Seed=-1"
  hole_rectangle_no_half_widths "'Discretization/Holes/cut/Half Widths' must be positive on every axis" "Discretization/Holes/cut/Shape=Rectangle"
  set_bool_garbage "'yes' is not true or false" "Output/VTK=yes"
  set_sublist_as_key "'Solver/Arc Length' is a sublist" "Solver/Arc Length=5"
  set_hexadecimal "'0x10' is not a number" "Material/Young's Modulus=0x10")
perinox_bad_input(spacing_too_small ${TINY} "'Discretization/Spacing' = 1e-300 gives more than 50000000 particles along x"
  --set "Discretization/Particles={}" --set "Discretization/Spacing=1e-300")
perinox_bad_input(spacing_not_dividing ${TINY} "'Discretization/Spacing' = 0.07 does not divide the box along x"
  --set "Discretization/Particles={}" --set "Discretization/Spacing=0.07")
perinox_bad_input(reference_stretch_negative ${TINY} "'Reference/Stretch' must be in [0.01, 100], not"
  --set "Reference/Type=Uniform Stretch" --set "Reference/Stretch=-1")
perinox_bad_sets(${XML}/tension_block.xml
  region_negative_thickness "'Regions/right end/Thickness' must be >= 0" "Regions/right end/Thickness=-1")

# Character references in any form XML allows (decimal and hexadecimal, beyond Latin-1) are read:
# Teuchos' parser takes only decimal ones below 256, so the scene reader writes the others as UTF-8.
file(READ ${CMAKE_CURRENT_SOURCE_DIR}/bad_input/tiny.xml PERINOX_TINY_SCENE)
string(REPLACE "value=\"Tiny tension block (test)\"" "value=\"A &amp; B &#233;&#x4e2d;&#x41;\""
  PERINOX_REFS_SCENE "${PERINOX_TINY_SCENE}")
file(WRITE ${CMAKE_CURRENT_BINARY_DIR}/character_references.xml "${PERINOX_REFS_SCENE}")
add_test(NAME scene_character_references COMMAND ${Python3_EXECUTABLE} ${CMAKE_CURRENT_SOURCE_DIR}/check_title.py
  --title "A & B U+00e9U+4e2dA" -- ${mpi_bom} $<TARGET_FILE:perinox> run ${CMAKE_CURRENT_BINARY_DIR}/character_references.xml
  --output ${PERINOX_TEST_OUT}/scene_character_references --quiet)
set_tests_properties(scene_character_references PROPERTIES ENVIRONMENT "${PERINOX_TEST_ENV};PERINOX_PLOT_SCRIPT=" LABELS unit)

# Built distributed (Discretization/Construction = Distributed, issue 17) on 2-3 ranks: a failure
# that only some ranks' shares contain (the conflicting DOFs or the fictitious particles sit on one
# or two ranks) is the same one sentence on every rank, exit code 2, nothing written, no hang; the
# rigid-body check summed over the ranks; what only lattices support refused.
function(perinox_bad_input_distributed name np scene message)
  perinox_mpi_command(mpi ${np})
  add_test(NAME badinput_${name} COMMAND ${Python3_EXECUTABLE} ${PERINOX_CHECK} --out ${PERINOX_TEST_OUT}/badinput_${name}
    --exit-code 2 --message "${message}" --no-output --
    ${mpi} $<TARGET_FILE:perinox> run ${scene} --output ${PERINOX_TEST_OUT}/badinput_${name}
    --set Discretization/Construction=Distributed ${ARGN})
  set_tests_properties(badinput_${name} PROPERTIES ENVIRONMENT "${PERINOX_TEST_ENV}" LABELS "unit;badinput;mpi"
    PROCESSORS ${np} TIMEOUT 120)
endfunction()
perinox_bad_input_distributed(distributed_bc_conflict 3 ${TINY} "boundary conditions 'fix' and 'pull' ${CONFLICT} (0 and 0.0001)"
  --set "Boundary Conditions/pull/Region=left")
perinox_bad_input_distributed(distributed_load_on_fictitious 3 ${TINY} "load 'tip load' acts on fictitious particles"
  --set "Loads/tip load/Region=right")
perinox_bad_input_distributed(distributed_no_rigid_constraint 3 ${BAD}/no_constraint.xml "do not prevent rigid-body motion")
# A particle file read distributed: each rank reads its slice of the bytes, and a bad line in any
# slice is refused on every rank with the message of a whole-file read (the same line number).
perinox_bad_input_distributed(distributed_particle_file_nul 3 ${GEN}/particle_file_nul.xml "nul_particles.txt:10: contains a NUL byte")
perinox_bad_input_distributed(distributed_particle_file_late 3 ${GEN}/particle_file_late_garbage.xml
  "late_garbage_particles.txt:200: '1.0x' is not a number")
perinox_bad_input(particle_file_late ${GEN}/particle_file_late_garbage.xml "late_garbage_particles.txt:200: '1.0x' is not a number")
# Finite but absurd magnitudes where a key has a physical range (the runs converged and printed
# e_u = -nan): one sentence naming the key and the range.
perinox_bad_input(reference_stretch_huge ${TINY} "'Reference/Stretch' must be in [0.01, 100], not"
  --set "Reference/Type=Uniform Stretch" --set "Reference/Stretch=1e300")
perinox_bad_input(field_beta_huge ${PROJECT_SOURCE_DIR}/xml/bar1d_variable_modulus.xml "'Material/Field Beta' must be in (0, 1], not 1e+300 (a strain)"
  --set "Material/Field Beta=1e300")
