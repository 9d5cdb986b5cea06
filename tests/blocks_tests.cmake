# Blocks with their own materials (ProblemSpec::blocks, the scene's Blocks; docs/exodus.md,
# docs/validation.md "Blocks with their own materials"). Included by tests/CMakeLists.txt.

# Bi-material patch test (tests/scenes/bimaterial_patch.xml): two layers, E = 1 and 3 GPa, the
# same nu, pulled along the layers. The exact solution u = (0.001 x, -0.0003 y) is also the exact
# discrete one (see the scene), so e_u and the reaction sum_k E_k A_k 0.001 = 8e5 N are bounded at
# round-off: measured e_u = 5.1e-14 and reaction 9.5e-14 relative (1 rank, direct), 5.0e-14 and
# 2.6e-14 (2 ranks, the scalable preset, whose lattice-FEM auxiliary matrix is assembled per
# block); bounds 1e-12 and 1e-12 (1e-10 for the Krylov run, which stops at its own tolerance).
perinox_run_test(NAME blocks_patch_np1 SCENE ../tests/scenes/bimaterial_patch.xml
  CHECK --converged --max-error 1e-12 --probe reaction 0 8e5 1e-12 LABELS "unit;verification")
perinox_run_test(NAME blocks_patch_scalable_np2 SCENE ../tests/scenes/bimaterial_patch.xml NP 2
  SETS "Solver/Linear Solver Preset=scalable"
  CHECK --converged --max-error 1e-10 --probe reaction 0 8e5 1e-10 LABELS "unit;verification")

# Two-material bar in series (tests/scenes/bimaterial_bar.xml) against the closed form: measured
# (80 x 8 particles, delta = 2.015 dx) block strains between probes away from the layers +2.8e-5
# and +1.8e-4 of R / (E_k A) (bound 1e-3), interface displacement +4.6e-4 (bound 5e-3), reaction
# -3.1 % (bound 5 %: the rigid grips' nonlocal boundary layer, first order: -1.6 % at 160 x 16).
perinox_run_test(NAME blocks_bar SCENE ../tests/scenes/bimaterial_bar.xml CHECK --converged
  FIXTURE_SETUP blocks_bar LABELS "unit;verification")
add_test(NAME blocks_bar_closed_form COMMAND ${Python3_EXECUTABLE} ${CMAKE_CURRENT_SOURCE_DIR}/check_blocks_bar.py
  ${PERINOX_TEST_OUT}/blocks_bar --U 0.001 --A 0.2 --E1 1e9 --E2 4e9 --L1 0.9 --L2 0.9
  --probes a1=0.3125 b1=0.6875 a2=1.3125 b2=1.6875 --strain-rtol 1e-3 --interface-rtol 5e-3 --reaction-rtol 0.05)
set_tests_properties(blocks_bar_closed_form PROPERTIES LABELS "unit;verification" FIXTURES_REQUIRED blocks_bar)

# Refused block input: one sentence naming the file and key, exit code 2, nothing written.
set(PATCH ${PROJECT_SOURCE_DIR}/tests/scenes/bimaterial_patch.xml)
perinox_bad_sets(${PATCH}
  blocks_unknown_key "unknown key 'Blocks/lower/Colour'" "Blocks/lower/Colour=red"
  blocks_unknown_material_key "unknown key 'Blocks/upper/Material/Young'" "Blocks/upper/Material/Young=5"
  blocks_bad_model "'Blocks/upper/Material/Model' must be Hencky or Small Strain, not 'Neo'" "Blocks/upper/Material/Model=Neo"
  blocks_nu_half "'Blocks/upper/Material/Poisson's Ratio' must be in (-1, 0.5), not 0.5" "Blocks/upper/Material/Poisson's Ratio=0.5"
  blocks_negative_modulus "'Blocks/upper/Material/Young's Modulus' must be positive, not -1" "Blocks/upper/Material/Young's Modulus=-1"
  blocks_negative_G "'Blocks/upper/Stabilization/G' must be >= 0, not -0.1" "Blocks/upper/Stabilization/G=-0.1"
  blocks_no_entry "block 1 (320 particles) has no entry under 'Blocks'" "Blocks/lower/Id=3"
  blocks_no_particles "block 'extra' names block 7, which has no particle" "Blocks/extra/Id=7"
  blocks_duplicate_id "blocks 'upper' and 'extra' both name block 2" "Blocks/extra/Id=2"
  blocks_no_id "block 'extra' needs exactly one of Name and Id" "Blocks/extra/Material/Young's Modulus=2e9"
  blocks_negative_id "'Blocks/lower/Id' must be >= 0" "Blocks/lower/Id=-4"
  blocks_half_box "block 'upper' needs both Box Min and Box Max, or neither" "Blocks/upper/Box Max={}"
  blocks_box_length "'Blocks/upper/Box Min' has 3 entries but needs 0 or 2" "Blocks/upper/Box Min={0, 0, 0}"
  blocks_damage_disabled "'Blocks/upper/Damage' is given but 'Damage/Enabled' is false" "Blocks/upper/Damage/Critical Stretch=0.01")
perinox_bad_input(blocks_name_on_lattice ${PATCH} "'Blocks/upper/Name' names a block, but only Exodus blocks have names"
  --set "Blocks/upper/Id=-1" --set "Blocks/upper/Name=top")
perinox_bad_input(blocks_box_overlap ${PATCH} "block boxes must not overlap"
  --set "Blocks/extra/Id=3" --set "Blocks/extra/Box Min={0, 0}" --set "Blocks/extra/Box Max={0.5, 0.3}")
perinox_bad_input(blocks_G_without_stabilization ${PATCH}
  "'Blocks/upper/Stabilization/G' is set but 'Model/Stabilization' is None" --set "Model/Stabilization=None" --set "Model/G=0")
perinox_bad_input(blocks_damage_order ${PATCH} "'Blocks/upper/Damage/Softening Start' and 'Blocks/upper/Damage/Critical Stretch' must satisfy 0 < s_min < s_cr"
  --set "Damage/Enabled=true" --set "Blocks/upper/Damage/Critical Stretch=0.001")
perinox_bad_input(blocks_damage_stall ${PATCH} "compares raw stretches across blocks"
  --set "Damage/Enabled=true" --set "Damage/On Stall=Break Most Stretched" --set "Blocks/upper/Damage/Critical Stretch=0.01")
# A modulus so large that the stabilisation's micromodulus overflows: one sentence naming the block
# (found by fuzz_inputs; it named a C++ function before).
perinox_bad_input(blocks_modulus_overflow ${CMAKE_CURRENT_SOURCE_DIR}/scenes/bimaterial_bar.xml
  "the stabilisation's micromodulus C of block 2 is not finite" --set "Blocks/stiff/Material/Young's Modulus=1e308")
