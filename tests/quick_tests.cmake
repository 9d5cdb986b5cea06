# The `quick` label (docs/testing.md): every package exercised in under a minute on 2 cores, for a
# developer's loop (ctest -L quick); fixtures the tests need run with them. Included by the
# top-level CMakeLists.txt before the packages, since each directory labels its own tests.
perinox_quick_tests(
  # packages, alone
  core_lattice core_families core_particle_file core_regions material_tangent material_analytic material_validation
  model_tangent stepping_load_stepper stepping_arc_length evaluator_jacobian evaluator_jacobian_np2 partition_np2
  solver_mumps solver_two_stage solver_auto_choice io_exodus_mesh derivative_cantilever_np1 derivative_tension_block_np2
  # the driver: verification, ranks, damage, matrix-free multigrid, stress points, arc length, meshes
  verify_cantilever verify_tension_block verify_hydrostatic_scene mpi_cantilever_np2 damage_detach_np1
  scalable_mf_tension_block_np1 stresspoints_tension_block_np1 hard_shallow_arch exodus_bar_np1
  # bad input, untrusted files, Peridigm decks
  badinput_unknown_key badinput_malformed_xml badinput_exodus_stray_element_np2 badinput_checkpoint_inputs
  peridigm_deck_qs_np1 peridigm_deck_qs_np1_gold badinput_peridigm_quadratic_value)
