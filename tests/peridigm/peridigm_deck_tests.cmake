# Peridigm's own verification decks run as Peridigm ships them (validation/peridigm_decks: deck,
# mesh, gold file), through `perinox run deck.xml`, and compared with the gold files by
# tests/check_peridigm_gold.py: Peridigm's hypoelastic law at the decks' stretch reproduces the
# gold reactions to 1e-6 (measured 1e-12), and perinox's Hencky answer differs from them by the
# difference of the two laws computed there, to 1e-6 (measured 1e-11): reactions at every step,
# displacements particle by particle. The quasi-static deck on 1 and 2 ranks and in its YAML form;
# the fully prescribed one (Verlet, no free unknown: its time steps are load steps). Bad decks:
# one sentence naming the key, exit 2, nothing written. Included by tests/CMakeLists.txt.
set(pd_decks ${PROJECT_SOURCE_DIR}/validation/peridigm_decks)
set(pd_qs ${pd_decks}/ElasticCorrespondenceQSTension)
set(pd_fp ${pd_decks}/ElasticCorrespondenceFullyPrescribedTension)
set(pd_qs_check --gold ${pd_qs}/ElasticCorrespondenceQSTension_gold.e --E 200e9 --nu 0.3 --strain 0.001 --steps 2 --lateral free)
foreach(case "qs;1;${pd_qs}/ElasticCorrespondenceQSTension.xml" "qs;2;${pd_qs}/ElasticCorrespondenceQSTension.xml"
             "qs_yaml;1;${CMAKE_CURRENT_SOURCE_DIR}/peridigm/decks/ElasticCorrespondenceQSTension.yaml"
             "fully_prescribed;1;${pd_fp}/ElasticCorrespondenceFullyPrescribedTension.xml"
             "fully_prescribed;3;${pd_fp}/ElasticCorrespondenceFullyPrescribedTension.xml")
  list(GET case 0 tag)
  list(GET case 1 np)
  list(GET case 2 deck)
  set(name peridigm_deck_${tag}_np${np})
  perinox_mpi_command(mpi ${np})
  add_test(NAME ${name} COMMAND ${Python3_EXECUTABLE} ${PERINOX_CHECK} --out ${PERINOX_TEST_OUT}/${name} --converged --
    ${mpi} $<TARGET_FILE:perinox> run ${deck} --output ${PERINOX_TEST_OUT}/${name} --quiet)
  set(labels verification)
  if(np GREATER 1)
    list(APPEND labels mpi)
  endif()
  set_tests_properties(${name} PROPERTIES ENVIRONMENT "${PERINOX_TEST_ENV};PERINOX_PLOT_SCRIPT=" LABELS "${labels}"
    PROCESSORS ${np} FIXTURES_SETUP ${name})
  if(tag STREQUAL "fully_prescribed")
    set(check --gold ${pd_fp}/ElasticCorrespondenceFullyPrescribedTension_gold.e --E 200e9 --nu 0 --strain 0.001 --steps 5 --lateral held)
  else()
    set(check ${pd_qs_check})
  endif()
  add_test(NAME ${name}_gold COMMAND ${Python3_EXECUTABLE} ${CMAKE_CURRENT_SOURCE_DIR}/check_peridigm_gold.py
    --out ${PERINOX_TEST_OUT}/${name} ${check})
  set_tests_properties(${name}_gold PROPERTIES LABELS "${labels}" FIXTURES_REQUIRED ${name})
endforeach()

set(pd_bad ${CMAKE_CURRENT_SOURCE_DIR}/peridigm/decks)
# A body force (Peridigm's Body Force condition, a force per volume): -1e9 t N/m^3 in y on the top
# grip's 96 particles of 0.015625 m^3, the bottom grip held: the bottom block reacts +1.5e9 N at
# t = 1 (equilibrium; to Newton's tolerance, 1e-10 of the reaction).
perinox_mpi_command(mpi1 1)
add_test(NAME peridigm_deck_body_force COMMAND ${Python3_EXECUTABLE} ${PERINOX_CHECK} --out ${PERINOX_TEST_OUT}/peridigm_deck_body_force
  --converged --probe Bottom_Reaction_Force 1 1.5e9 1e-9 --
  ${mpi1} $<TARGET_FILE:perinox> run ${pd_bad}/body_force.xml --output ${PERINOX_TEST_OUT}/peridigm_deck_body_force --quiet)
# Elastic Plastic Correspondence (yield stress 200 MPa, hardening modulus 2 GPa, E = 200 GPa):
# the bar pulled to 1 % strain in uniaxial stress. Closed form of J2 at finite strain with the
# exponential map: eps_p = (E ln 1.01 - sigma_y) / (E + H) = 8.8617e-3, tau = sigma_y + H eps_p,
# reaction P A = tau / 1.01 x 1 m^2 = 2.15567749933e8 N (measured to 4e-13); quadratic Newton.
add_test(NAME peridigm_deck_plastic COMMAND ${Python3_EXECUTABLE} ${PERINOX_CHECK} --out ${PERINOX_TEST_OUT}/peridigm_deck_plastic
  --converged --quadratic --probe Top_Reaction_Force 1 2.1556774993268913e8 1e-8 --
  ${mpi1} $<TARGET_FILE:perinox> run ${pd_bad}/plastic_bar.xml --output ${PERINOX_TEST_OUT}/peridigm_deck_plastic --quiet)
set_tests_properties(peridigm_deck_body_force peridigm_deck_plastic PROPERTIES ENVIRONMENT "${PERINOX_TEST_ENV};PERINOX_PLOT_SCRIPT="
  LABELS verification)
perinox_bad_input(peridigm_verlet_free ${pd_bad}/verlet_free.xml "'Solver/Verlet' is explicit dynamics, which perinox does not solve")
perinox_bad_input(peridigm_quadratic_value ${pd_bad}/quadratic_value.xml
  "'Boundary Conditions/Bottom Y/Value': '0.001*y*y*t' is not of the form t (a + b x + c y + d z)")
perinox_bad_input(peridigm_function_value ${pd_bad}/function_value.xml "uses the name 'sin' at character 7")
perinox_bad_input(peridigm_ordinary_material ${pd_bad}/ordinary_material.xml "'Materials/Steel/Material Model' is 'Elastic'")
perinox_bad_input(peridigm_constants_disagree ${pd_bad}/constants_disagree.xml "'Materials/Steel/Bulk Modulus' is 100000000000 but")
perinox_bad_input(peridigm_plastic_no_yield ${pd_bad}/plastic_no_yield.xml "'Materials/Steel/Yield Stress' is missing")
perinox_bad_input(peridigm_damage_models ${pd_bad}/damage_models.xml "has 'Damage Models', which perinox does not translate")
perinox_bad_input(peridigm_not_a_deck ${pd_bad}/not_a_deck.yaml "not the map 'Peridigm:' a Peridigm deck holds")
# Text File decks and node sets a deck defines (numbers inline or in node-set files: a text
# mesh's line numbers, an Exodus mesh's element number map) select the same particles as the
# Exodus deck they are written from: every probe agrees to round-off (check_text_mesh_deck.py);
# on two ranks with the distributed construction too.
add_test(NAME peridigm_deck_text_mesh COMMAND ${Python3_EXECUTABLE} ${CMAKE_CURRENT_SOURCE_DIR}/peridigm/check_text_mesh_deck.py
  $<TARGET_FILE:perinox> ${PROJECT_SOURCE_DIR} ${PERINOX_TEST_OUT}/peridigm_deck_text_mesh)
perinox_mpi_command(pd_mpi2 2)
add_test(NAME peridigm_deck_text_mesh_np2 COMMAND ${Python3_EXECUTABLE} ${CMAKE_CURRENT_SOURCE_DIR}/peridigm/check_text_mesh_deck.py
  $<TARGET_FILE:perinox> ${PROJECT_SOURCE_DIR} ${PERINOX_TEST_OUT}/peridigm_deck_text_mesh_np2 --mpi ${pd_mpi2} --)
set_tests_properties(peridigm_deck_text_mesh peridigm_deck_text_mesh_np2 PROPERTIES ENVIRONMENT "${PERINOX_TEST_ENV}" LABELS verification)
set_tests_properties(peridigm_deck_text_mesh_np2 PROPERTIES PROCESSORS 2)
set(pd_text ${pd_bad}/text)
perinox_bad_input(peridigm_node_set_zero ${pd_text}/node_set_zero.xml "'Boundary Conditions/Node Set 1' lists '0'; node numbers are whole numbers from 1")
perinox_bad_input(peridigm_node_set_beyond ${pd_text}/node_set_beyond.xml "holds 9, but the particle file has 8 particles")
perinox_bad_input(peridigm_node_set_missing_file ${pd_text}/node_set_missing_file.xml "names the node-set file 'nowhere.txt', which does not exist")
perinox_bad_input(peridigm_undefined_node_set ${pd_text}/undefined_node_set.xml "is 'nodelist_1', which the deck does not define")
perinox_bad_input(peridigm_text_mesh_columns ${pd_text}/four_columns.xml "cube_four_columns.txt:4: expected 5 numbers \"x y z block volume\"")
perinox_bad_input(peridigm_omit_bonds ${pd_text}/omit_bonds.xml "perinox keeps the bonds between blocks")
# A scene's Ids region: numbers from 1, within the particle file, not on a lattice.
perinox_bad_input(ids_region_zero ${PROJECT_SOURCE_DIR}/tests/scenes/tension_block_file.xml "holds 0; particle numbers start at 1"
  --set "Regions/numbered/Type=Ids" --set "Regions/numbered/Ids={3,0}")
perinox_bad_input(ids_region_on_lattice ${PROJECT_SOURCE_DIR}/xml/tension_block.xml "(Type = Ids) numbers particles of a particle file or an Exodus mesh"
  --set "Regions/numbered/Type=Ids" --set "Regions/numbered/Ids={3}")
perinox_bad_input(ids_region_exodus_unknown_id ${pd_bad}/../../../validation/peridigm_decks/ElasticCorrespondenceQSTension/ElasticCorrespondenceQSTension.xml
  "holds 385, which is no element's id in the mesh's element number map" --set "Regions/numbered/Type=Ids" --set "Regions/numbered/Ids={289,385}")
# The scene a deck made (the run folder's scene.resolved.xml) is a scene perinox reads as it is.
add_test(NAME peridigm_deck_resolved_scene COMMAND $<TARGET_FILE:perinox> check ${PERINOX_TEST_OUT}/peridigm_deck_qs_np1/scene.resolved.xml)
set_tests_properties(peridigm_deck_resolved_scene PROPERTIES ENVIRONMENT "${PERINOX_TEST_ENV}" LABELS verification
  FIXTURES_REQUIRED peridigm_deck_qs_np1 PASS_REGULAR_EXPRESSION "is a valid scene")
