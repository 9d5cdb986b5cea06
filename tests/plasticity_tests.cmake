# J2 plasticity through the whole driver (docs/plasticity.md). Included by tests/CMakeLists.txt.

# Uniaxial strain past yield against the closed form, in the middle of the body: the error is the
# O(dx) boundary layer of the nonlocal model (2.3-2.9 % at 40 x 20, 1.2-1.6 % at 80 x 40, measured),
# so the tolerance halves with the spacing (first-order convergence to the continuum solution).
# Newton must converge quadratically with the algorithmic tangent.
perinox_run_test(NAME verify_plastic_uniaxial_strain SCENE plastic_uniaxial_strain.xml
  CHECK --converged --quadratic LABELS verification FIXTURE_SETUP plastic_us)
add_test(NAME verify_plastic_uniaxial_strain_closed_form COMMAND ${Python3_EXECUTABLE}
  ${CMAKE_CURRENT_SOURCE_DIR}/check_plastic_uniaxial_strain.py ${PERINOX_TEST_OUT}/verify_plastic_uniaxial_strain --rtol 0.035)
set_tests_properties(verify_plastic_uniaxial_strain_closed_form PROPERTIES LABELS verification FIXTURES_REQUIRED plastic_us)
perinox_run_test(NAME verify_plastic_uniaxial_strain_refined SCENE plastic_uniaxial_strain.xml
  SETS "Discretization/Particles={80,40}"
  CHECK --converged --quadratic LABELS verification FIXTURE_SETUP plastic_us_refined)
add_test(NAME verify_plastic_uniaxial_strain_refined_closed_form COMMAND ${Python3_EXECUTABLE}
  ${CMAKE_CURRENT_SOURCE_DIR}/check_plastic_uniaxial_strain.py ${PERINOX_TEST_OUT}/verify_plastic_uniaxial_strain_refined --rtol 0.0175)
set_tests_properties(verify_plastic_uniaxial_strain_refined_closed_form PROPERTIES LABELS verification
  FIXTURES_REQUIRED plastic_us_refined)

# A load path: loading to 1 %, unloading to zero strain (reverse yielding on the way) and
# reloading to 1.5 %, against the closed form replayed along the run's steps. Without the
# committed state (every step from the virgin state) the final plastic strain would be half of it.
perinox_run_test(NAME verify_plastic_load_path SCENE plastic_uniaxial_strain.xml
  SETS "Solver/Load Path={1, 0, 1.5}" "Solver/Load Steps=4"
  CHECK --converged --quadratic LABELS verification FIXTURE_SETUP plastic_path)
add_test(NAME verify_plastic_load_path_closed_form COMMAND ${Python3_EXECUTABLE}
  ${CMAKE_CURRENT_SOURCE_DIR}/check_plastic_uniaxial_strain.py ${PERINOX_TEST_OUT}/verify_plastic_load_path --rtol 0.035)
set_tests_properties(verify_plastic_load_path_closed_form PROPERTIES LABELS verification FIXTURES_REQUIRED plastic_path)

# Every solver path on the plastic tangent gives the same steps: matrix-free with the scalable
# preconditioner, GMRES-ILU on the assembled Jacobian, Jacobian-free Newton-Krylov (its J v by
# differences of the residual at the committed state), and two ranks (rank independence).
foreach(variant
    "scalable_mf|Solver/Linear Solver Preset=scalable|Solver/Jacobian=Matrix-Free"
    "gmres_ilu|Solver/Linear Solver Preset=gmres-ilu"
    "jfnk|Solver/Linear Solver Preset=gmres-ilu|Solver/Jacobian=Jacobian-Free")
  string(REPLACE "|" ";" parts "${variant}")
  list(POP_FRONT parts name)
  perinox_run_test(NAME plastic_${name} SCENE plastic_uniaxial_strain.xml SETS ${parts}
    CHECK --converged LABELS verification FIXTURE_SETUP plastic_${name})
  add_test(NAME plastic_${name}_compare COMMAND ${Python3_EXECUTABLE} ${CMAKE_CURRENT_SOURCE_DIR}/compare_runs.py
    --rtol 1e-8 ${PERINOX_TEST_OUT}/verify_plastic_uniaxial_strain ${PERINOX_TEST_OUT}/plastic_${name})
  set_tests_properties(plastic_${name}_compare PROPERTIES LABELS verification FIXTURES_REQUIRED "plastic_us;plastic_${name}")
endforeach()
perinox_run_test(NAME plastic_uniaxial_strain_np2 SCENE plastic_uniaxial_strain.xml NP 2
  CHECK --converged LABELS verification FIXTURE_SETUP plastic_np2)
add_test(NAME plastic_uniaxial_strain_np2_compare COMMAND ${Python3_EXECUTABLE} ${CMAKE_CURRENT_SOURCE_DIR}/compare_runs.py
  --rtol 1e-10 ${PERINOX_TEST_OUT}/verify_plastic_uniaxial_strain ${PERINOX_TEST_OUT}/plastic_uniaxial_strain_np2)
set_tests_properties(plastic_uniaxial_strain_np2_compare PROPERTIES LABELS "verification;mpi" FIXTURES_REQUIRED "plastic_us;plastic_np2")

# Checkpoints hold the committed state: a run resumed on one rank is bit for bit the run that
# wrote the checkpoint; on two ranks (the state moves with its particle) it agrees to round-off.
# The checkpoint is written mid-unloading (step 7 of 12 on the load path), where the state, not
# the displacement, decides what comes next.
set(PLASTIC_PATH "Solver/Load Path={1, 0, 1.5}" "Solver/Load Steps=4")
perinox_run_test(NAME plastic_checkpoint_np1 SCENE plastic_uniaxial_strain.xml SETS ${PLASTIC_PATH}
  ARGS --checkpoint-steps 7
  CHECK --converged LABELS verification FIXTURE_SETUP plastic_checkpoint)
perinox_run_test(NAME plastic_restart_np1 SCENE plastic_uniaxial_strain.xml SETS ${PLASTIC_PATH}
  ARGS --restart ${PERINOX_TEST_OUT}/plastic_checkpoint_np1.checkpoint
  CHECK --converged LABELS verification FIXTURE_REQUIRED plastic_checkpoint FIXTURE_SETUP plastic_restart_1)
add_test(NAME plastic_restart_np1_exact COMMAND ${Python3_EXECUTABLE} ${CMAKE_CURRENT_SOURCE_DIR}/check_restart.py
  --from-step 7 --exact ${PERINOX_TEST_OUT}/plastic_checkpoint_np1 ${PERINOX_TEST_OUT}/plastic_restart_np1)
set_tests_properties(plastic_restart_np1_exact PROPERTIES LABELS verification FIXTURES_REQUIRED "plastic_checkpoint;plastic_restart_1")
perinox_run_test(NAME plastic_restart_np2 SCENE plastic_uniaxial_strain.xml NP 2
  SETS ${PLASTIC_PATH} "Discretization/Construction=Distributed"
  ARGS --restart ${PERINOX_TEST_OUT}/plastic_checkpoint_np1.checkpoint
  CHECK --converged LABELS verification FIXTURE_REQUIRED plastic_checkpoint FIXTURE_SETUP plastic_restart_2)
add_test(NAME plastic_restart_np2_compare COMMAND ${Python3_EXECUTABLE} ${CMAKE_CURRENT_SOURCE_DIR}/check_restart.py
  --from-step 7 --rtol 1e-10 ${PERINOX_TEST_OUT}/plastic_checkpoint_np1 ${PERINOX_TEST_OUT}/plastic_restart_np2)
set_tests_properties(plastic_restart_np2_compare PROPERTIES LABELS "verification;mpi" FIXTURES_REQUIRED "plastic_checkpoint;plastic_restart_2")
# A checkpoint without the states (written before the material had history, or damaged) is refused.
add_test(NAME plastic_checkpoint_strip COMMAND ${Python3_EXECUTABLE} ${CMAKE_CURRENT_SOURCE_DIR}/strip_checkpoint_states.py
  ${PERINOX_TEST_OUT}/plastic_checkpoint_np1.checkpoint ${PERINOX_TEST_OUT}/plastic_checkpoint_stripped)
set_tests_properties(plastic_checkpoint_strip PROPERTIES LABELS "unit;badinput" FIXTURES_REQUIRED plastic_checkpoint
  FIXTURES_SETUP plastic_stripped)
perinox_bad_input(restart_without_material_state ${XML}/plastic_uniaxial_strain.xml "holds no material state for particle"
  --set "Solver/Load Path={1, 0, 1.5}" --set "Solver/Load Steps=4" --restart ${PERINOX_TEST_OUT}/plastic_checkpoint_stripped)
set_tests_properties(badinput_restart_without_material_state PROPERTIES FIXTURES_REQUIRED plastic_stripped)

# Impossible plastic parameters: one sentence naming the key, nothing written.
perinox_bad_sets(${XML}/plastic_uniaxial_strain.xml
  plastic_zero_yield "'Material/Yield Stress' must be positive with Plasticity = J2" "Material/Yield Stress=0"
  plastic_negative_hardening "'Material/Hardening Modulus' must be" "Material/Hardening Modulus=-1e9"
  plastic_unknown_kind "Plasticity" "Material/Plasticity=J3")
perinox_bad_input(plastic_voce_saturation_below_yield ${XML}/plastic_uniaxial_strain.xml
  "'Material/Saturation Stress' must be at least 'Material/Yield Stress' with Hardening = Voce"
  --set "Material/Hardening=Voce" --set "Material/Saturation Stress=1e8" --set "Material/Saturation Rate=10")
perinox_bad_input(plastic_voce_zero_rate ${XML}/plastic_uniaxial_strain.xml
  "'Material/Saturation Rate' must be positive with Hardening = Voce"
  --set "Material/Hardening=Voce" --set "Material/Saturation Stress=4e8")
perinox_bad_sets(${XML}/plastic_uniaxial_strain.xml
  load_path_flat_segment "'Solver/Load Path' entry 2 (1) equals the load factor before it" "Solver/Load Path={1, 1, 0}"
  load_path_starts_at_zero "'Solver/Load Path' entry 1 (0) equals the load factor before it" "Solver/Load Path={0, 1}")
perinox_bad_input(load_path_with_arc_length ${XML}/plastic_uniaxial_strain.xml "'Solver/Load Path' needs 'Solver/Continuation' = Load Stepping"
  --set "Solver/Load Path={1, 0}" --set "Solver/Continuation=Arc Length")
perinox_bad_input(plastic_probe_on_elastic_scene ${XML}/plastic_uniaxial_strain.xml
  "probe 'plastic strain' measures the plastic strain, but no material of the scene is plastic"
  --set "Material/Plasticity=None")
perinox_bad_input(ductile_without_critical_value ${XML}/plastic_uniaxial_strain.xml
  "'Damage/Criterion' breaks bonds by plastic strain: give 'Damage/Critical Plastic Strain' > 0"
  --set "Damage/Enabled=true" --set "Damage/Criterion=Plastic Strain")
perinox_bad_input(ductile_value_without_criterion ${XML}/plastic_uniaxial_strain.xml
  "'Damage/Critical Plastic Strain' is set but 'Damage/Criterion' is Stretch"
  --set "Damage/Enabled=true" --set "Damage/Critical Plastic Strain=0.01")
perinox_bad_input(ductile_without_plastic_material ${XML}/plastic_uniaxial_strain.xml
  "breaks bonds by plastic strain (Critical Plastic Strain), but no material is plastic"
  --set "Material/Plasticity=None" --set "Probes/plastic strain/Quantity=Displacement" --set "Damage/Enabled=true"
  --set "Damage/Criterion=Plastic Strain" --set "Damage/Critical Plastic Strain=0.01")

# A ductile crack: the plate with a hole in J2 steel, bonds broken by the plastic strain of their
# ends. The crack runs through the ligaments from the hole to the free edges over several steps
# (check_ductile_crack.py), and two ranks break the same bonds in the same steps (the ends'
# plastic strains reach the ghosts by an Import) with the same probes to 1e-8.
perinox_run_test(NAME ductile_plate_np1 SCENE plate_hole_ductile.xml
  CHECK --converged LABELS verification FIXTURE_SETUP ductile_1)
add_test(NAME ductile_plate_crack_path COMMAND ${Python3_EXECUTABLE} ${CMAKE_CURRENT_SOURCE_DIR}/check_ductile_crack.py
  ${PERINOX_TEST_OUT}/ductile_plate_np1)
set_tests_properties(ductile_plate_crack_path PROPERTIES LABELS verification FIXTURES_REQUIRED ductile_1)
perinox_run_test(NAME ductile_plate_np2 SCENE plate_hole_ductile.xml NP 2
  CHECK --converged LABELS verification FIXTURE_SETUP ductile_2)
add_test(NAME ductile_plate_np2_compare COMMAND ${Python3_EXECUTABLE} ${CMAKE_CURRENT_SOURCE_DIR}/compare_runs.py
  --rtol 1e-8 --same-damage ${PERINOX_TEST_OUT}/ductile_plate_np1 ${PERINOX_TEST_OUT}/ductile_plate_np2)
set_tests_properties(ductile_plate_np2_compare PROPERTIES LABELS "verification;mpi" FIXTURES_REQUIRED "ductile_1;ductile_2")

# Arc length with a plastic material: the history is committed per accepted arc step; the run
# reaches load factor 1 through yield with quadratic correctors, matches the closed form as the
# load-stepped run does, and ends within 1e-4 of it (the boundary layer's points load
# non-proportionally, so their plastic strain depends a little on the steps: 3.9e-5 measured with
# 7 arc steps against 8 load steps).
perinox_run_test(NAME plastic_arc_length SCENE plastic_uniaxial_strain.xml
  SETS "Solver/Continuation=Arc Length" "Solver/Arc Length/Deflection Probe=right end" "Solver/Arc Length/Deflection Component=x"
  CHECK --converged --quadratic LABELS verification FIXTURE_SETUP plastic_arc)
add_test(NAME plastic_arc_length_closed_form COMMAND ${Python3_EXECUTABLE}
  ${CMAKE_CURRENT_SOURCE_DIR}/check_plastic_uniaxial_strain.py ${PERINOX_TEST_OUT}/plastic_arc_length --rtol 0.035)
set_tests_properties(plastic_arc_length_closed_form PROPERTIES LABELS verification FIXTURES_REQUIRED plastic_arc)
add_test(NAME plastic_arc_length_compare COMMAND ${Python3_EXECUTABLE} ${CMAKE_CURRENT_SOURCE_DIR}/compare_runs.py
  --rtol 1e-4 --final-only --load-factor-tol 1e-9 ${PERINOX_TEST_OUT}/verify_plastic_uniaxial_strain ${PERINOX_TEST_OUT}/plastic_arc_length)
set_tests_properties(plastic_arc_length_compare PROPERTIES LABELS verification FIXTURES_REQUIRED "plastic_us;plastic_arc")

# The 1D bar pulled, released past reverse yield and pulled again (xml/plastic_bar.xml): the
# reaction at every step against the closed form of uniaxial stress to 1e-8 (the stress-point bar
# keeps the strain uniform, so only Newton's tolerance separates them), the plastic strain of
# every particle, and two ranks against one.
perinox_run_test(NAME verify_plastic_bar SCENE plastic_bar.xml
  CHECK --converged --quadratic LABELS verification FIXTURE_SETUP plastic_bar)
add_test(NAME verify_plastic_bar_closed_form COMMAND ${Python3_EXECUTABLE} ${CMAKE_CURRENT_SOURCE_DIR}/check_plastic_bar.py
  ${PERINOX_TEST_OUT}/verify_plastic_bar)
set_tests_properties(verify_plastic_bar_closed_form PROPERTIES LABELS verification FIXTURES_REQUIRED plastic_bar)
perinox_run_test(NAME plastic_bar_np2 SCENE plastic_bar.xml NP 2
  CHECK --converged LABELS verification FIXTURE_SETUP plastic_bar_2)
add_test(NAME plastic_bar_np2_compare COMMAND ${Python3_EXECUTABLE} ${CMAKE_CURRENT_SOURCE_DIR}/compare_runs.py
  --rtol 1e-10 ${PERINOX_TEST_OUT}/verify_plastic_bar ${PERINOX_TEST_OUT}/plastic_bar_np2)
set_tests_properties(plastic_bar_np2_compare PROPERTIES LABELS "verification;mpi" FIXTURES_REQUIRED "plastic_bar;plastic_bar_2")

# The other return maps through the whole solver: plane stress (F33 solved in the return) along
# the load path, on one and two ranks; small strain with Voce hardening. Newton quadratic in every step.
perinox_run_test(NAME plastic_plane_stress_load_path SCENE plastic_uniaxial_strain.xml
  SETS "Material/Plane=Plane Stress" ${PLASTIC_PATH}
  CHECK --converged --quadratic LABELS verification FIXTURE_SETUP plastic_ps_1)
perinox_run_test(NAME plastic_plane_stress_load_path_np2 SCENE plastic_uniaxial_strain.xml NP 2
  SETS "Material/Plane=Plane Stress" ${PLASTIC_PATH}
  CHECK --converged LABELS verification FIXTURE_SETUP plastic_ps_2)
add_test(NAME plastic_plane_stress_np2_compare COMMAND ${Python3_EXECUTABLE} ${CMAKE_CURRENT_SOURCE_DIR}/compare_runs.py
  --rtol 1e-10 ${PERINOX_TEST_OUT}/plastic_plane_stress_load_path ${PERINOX_TEST_OUT}/plastic_plane_stress_load_path_np2)
set_tests_properties(plastic_plane_stress_np2_compare PROPERTIES LABELS "verification;mpi" FIXTURES_REQUIRED "plastic_ps_1;plastic_ps_2")
perinox_run_test(NAME plastic_small_strain_voce SCENE plastic_uniaxial_strain.xml
  SETS "Material/Model=Small Strain" "Material/Hardening=Voce" "Material/Saturation Stress=4e8" "Material/Saturation Rate=50"
  CHECK --converged --quadratic LABELS verification)

# The pictures of a plastic run with damage: deformed.png gains the damage and the plastic-strain
# panels (drivers/plot_result.py), and the plot script must not fail on the eqps columns.
perinox_mpi_command(mpi_plots_plastic 1)
add_test(NAME plots_drawn_plastic COMMAND ${Python3_EXECUTABLE} ${PERINOX_CHECK} --out ${PERINOX_TEST_OUT}/plots_drawn_plastic
  --converged --png deformed.png probes.png -- ${mpi_plots_plastic} $<TARGET_FILE:perinox> run
  ${PROJECT_SOURCE_DIR}/xml/plastic_uniaxial_strain.xml --output ${PERINOX_TEST_OUT}/plots_drawn_plastic --quiet)
set_tests_properties(plots_drawn_plastic PROPERTIES ENVIRONMENT "${PERINOX_TEST_ENV}" LABELS verification)

# A thick-walled cylinder under internal pressure (plane strain, perfect plasticity) to its limit
# load and past it: the load stepper converges up to the limit and stops there, naming it
# (Solver/Limit Load Ratio), and Newton stays quadratic. Against the closed forms
# (tests/check_plastic_vessel.py): first yield at the bore (0.4323 sigma_y; the run brackets it
# in [0.425, 0.430] sigma_y), the limit pressure (2/sqrt 3) sigma_y ln 2 = 0.8004 sigma_y
# (measured +6.6 %, +2.0 %, +0.9 % at 10, 20, 40 shells) within 3 % at the scene's 20 shells,
# and the elastic bore displacement (measured +9.8 %, +3.6 %, +1.9 %) within 5 %.
perinox_run_test(NAME verify_plastic_cylinder SCENE plastic_cylinder.xml
  CHECK --expect-from-scene ${XML}/plastic_cylinder.xml --quadratic LABELS verification FIXTURE_SETUP plastic_cylinder)
add_test(NAME verify_plastic_cylinder_closed_form COMMAND ${Python3_EXECUTABLE}
  ${CMAKE_CURRENT_SOURCE_DIR}/check_plastic_vessel.py ${PERINOX_TEST_OUT}/verify_plastic_cylinder --shape cylinder
  --E 200e9 --nu 0.3 --yield 250e6 --p-ref 250e6 --inner 1 --outer 2 --probe-radius 1.025
  --yield-tol 0.03 --limit-tol 0.03 --stiffness-tol 0.05)
set_tests_properties(verify_plastic_cylinder_closed_form PROPERTIES LABELS verification FIXTURES_REQUIRED plastic_cylinder)
# Two ranks stop at the same limit load with the same steps.
perinox_run_test(NAME plastic_cylinder_np2 SCENE plastic_cylinder.xml NP 2
  CHECK --expect-from-scene ${XML}/plastic_cylinder.xml LABELS verification FIXTURE_SETUP plastic_cylinder_np2)
add_test(NAME plastic_cylinder_np2_compare COMMAND ${Python3_EXECUTABLE} ${CMAKE_CURRENT_SOURCE_DIR}/compare_runs.py
  --rtol 1e-8 ${PERINOX_TEST_OUT}/verify_plastic_cylinder ${PERINOX_TEST_OUT}/plastic_cylinder_np2)
set_tests_properties(plastic_cylinder_np2_compare PROPERTIES LABELS "verification;mpi"
  FIXTURES_REQUIRED "plastic_cylinder;plastic_cylinder_np2")

# Arc length follows the cylinder past its limit load along the plateau of perfect plasticity, to
# a bore deflection 4.8 times the knee's: the load stays at 0.812-0.828 sigma_y (the closed form's
# 0.8004 + 1.5 .. 3.4 %; what rises is the stabilisation's residual stiffness, 0.18 % of the
# elastic one), within 4 %, and the correctors converge quadratically.
set(CYLINDER_ARC "Solver/Continuation=Arc Length" "Solver/Load Path={}" "Solver/Arc Length/Deflection Probe=bore point"
  "Solver/Arc Length/Deflection Component=x" "Solver/Arc Length/Target Deflection=0.02" "Solver/Arc Length/Max Steps=200"
  "Solver/Arc Length/Initial Arc Length=0.1")
perinox_run_test(NAME plastic_cylinder_arc_length SCENE plastic_cylinder.xml SETS ${CYLINDER_ARC}
  CHECK --converged --quadratic LABELS verification FIXTURE_SETUP plastic_cylinder_arc)
add_test(NAME plastic_cylinder_arc_length_plateau COMMAND ${Python3_EXECUTABLE}
  ${CMAKE_CURRENT_SOURCE_DIR}/check_plastic_vessel.py ${PERINOX_TEST_OUT}/plastic_cylinder_arc_length --arc --shape cylinder
  --E 200e9 --nu 0.3 --yield 250e6 --p-ref 250e6 --inner 1 --outer 2 --probe-radius 1.025 --limit-tol 0.04 --stiffness-tol 0.05)
set_tests_properties(plastic_cylinder_arc_length_plateau PROPERTIES LABELS verification FIXTURES_REQUIRED plastic_cylinder_arc)

# Radial Force and Limit Load Ratio refuse what they cannot mean, in one sentence.
perinox_bad_input(radial_force_with_value ${XML}/plastic_cylinder.xml "'Loads/pressure/Value' is not used by a Radial Force"
  --set "Loads/pressure/Value={1.0, 0.0}")
perinox_bad_input(radial_force_without_center ${XML}/plastic_cylinder.xml "'Loads/pressure/Center' is needed by a Radial Force"
  --set "Loads/pressure/Center={}")
perinox_bad_input(radial_force_zero ${XML}/plastic_cylinder.xml "'Loads/pressure/Magnitude' must be finite and non-zero"
  --set "Loads/pressure/Magnitude=0.0")
perinox_bad_input(radial_force_axis_in_2d ${XML}/plastic_cylinder.xml "'Loads/pressure/Axis' is for 3D scenes"
  --set "Loads/pressure/Axis={0.0, 1.0}")
perinox_bad_input(radial_force_keys_on_total_force ${XML}/plastic_cylinder.xml "belong to a Radial Force, not a Total Force"
  --set "Loads/pressure/Type=Total Force")
perinox_bad_input(radial_force_at_centre ${XML}/plastic_cylinder.xml "lies on its centre (or axis): it has no direction"
  --set "Loads/pressure/Center={1.025, 0.0}")
perinox_bad_input(limit_load_ratio_below_one ${XML}/plastic_cylinder.xml "'Solver/Limit Load Ratio' must be 0 (no check) or more than 1"
  --set "Solver/Limit Load Ratio=0.5")

# The plate with a hole loaded past yield and unloaded into reverse yielding, against CalculiX
# (CPE8R, *PLASTIC; validation/reference/plate_hole_plastic_fem*.csv from
# tools/ccx_plate_hole_plastic.py --refine 2 --increments 10, within 0.17 % of refine 1). The
# reaction at every step differs from the FE one by at most 22 %, 11 % and 5 % of the peak at
# 60 x 20, 120 x 40 (the scene) and 240 x 80 particles (first order; docs/plasticity.md), the
# plastic zone's area by +50 %, +20 %, +3 % and its eqps integral by -6 %, -3 %, -1.6 %; the
# bounds are those at 60 x 20 and at the scene's resolution, so a coarser run must be further off.
set(PLATE_FE ${PROJECT_SOURCE_DIR}/validation/reference/plate_hole_plastic_fem.csv)
set(PLATE_ZONE ${PROJECT_SOURCE_DIR}/validation/reference/plate_hole_plastic_fem_zone.csv)
# Each run: the name's suffix, the particles, the spacing, and the bounds on the reaction and the zone.
foreach(run "|120,40|1.25|0.12|0.22" "_coarse|60,20|2.5|0.23|0.52")
  string(REPLACE "|" ";" parts "${run}")
  list(GET parts 0 suffix)
  list(GET parts 1 particles)
  list(GET parts 2 spacing)
  list(GET parts 3 rtol)
  list(GET parts 4 zone_rtol)
  perinox_run_test(NAME verify_plate_hole_plastic${suffix} SCENE plate_hole_plastic.xml SETS "Discretization/Particles={${particles}}"
    CHECK --converged --quadratic LABELS verification FIXTURE_SETUP plate_hole_plastic${suffix})
  add_test(NAME verify_plate_hole_plastic${suffix}_fem COMMAND ${Python3_EXECUTABLE} ${CMAKE_CURRENT_SOURCE_DIR}/check_plate_hole_plastic.py
    ${PERINOX_TEST_OUT}/verify_plate_hole_plastic${suffix} ${PLATE_FE} --zone ${PLATE_ZONE} --spacing ${spacing} --rtol ${rtol}
    --zone-rtol ${zone_rtol})
  set_tests_properties(verify_plate_hole_plastic${suffix}_fem PROPERTIES LABELS verification FIXTURES_REQUIRED plate_hole_plastic${suffix})
endforeach()
