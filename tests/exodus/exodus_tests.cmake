# Exodus II meshes in and results out (docs/exodus.md). Included by tests/CMakeLists.txt when
# the Exodus library was found (scripts/setup.sh installs it, so CI always runs these).

# The reader on self-written meshes (closed-form volumes, node sets), bad meshes, and Peridigm's
# tensile_test.g against its particle file; on 1 and 3 ranks (each rank reads on its own).
# the copy kept in the repository (from ../shared/benchmarks, with its licence), so CI runs it too
set(PERINOX_TENSILE_DIR ${PROJECT_SOURCE_DIR}/validation/benchmarks/peridigm_tensile)
get_filename_component(PERINOX_TENSILE_DIR ${PERINOX_TENSILE_DIR} ABSOLUTE)
perinox_add_gtest(NAME io_exodus_mesh SOURCES exodus/test_exodus_mesh.cpp OWN_MAIN LIBS perinox_core MPI::MPI_CXX
  NPS 1 3 LABELS unit)
perinox_link_exodus(io_exodus_mesh)
target_include_directories(io_exodus_mesh PRIVATE ${CMAKE_CURRENT_SOURCE_DIR}/exodus)
if(EXISTS ${PERINOX_TENSILE_DIR}/tensile_test.g AND EXISTS ${PERINOX_TENSILE_DIR}/tensile_bar_points.txt)
  target_compile_definitions(io_exodus_mesh PRIVATE PERINOX_TENSILE_DIR="${PERINOX_TENSILE_DIR}")
else()
  message(STATUS "perinox: ${PERINOX_TENSILE_DIR}/tensile_test.g not found: the tensile-test comparison is not built")
endif()

# The meshes (and their closed-form particle files) the driver runs below read, written by a
# helper with the Exodus C API (tests/exodus/make_exodus_meshes.cpp), beside the test scenes so
# that the scenes' relative 'Mesh File' and 'Particle File' paths resolve.
set(EXO_DIR ${CMAKE_CURRENT_BINARY_DIR}/exodus_meshes)
file(MAKE_DIRECTORY ${EXO_DIR})
foreach(scene bar_exodus bar_points quad_exodus quad_points bimaterial_bar_exodus)
  configure_file(${CMAKE_CURRENT_SOURCE_DIR}/exodus/${scene}.xml ${EXO_DIR}/${scene}.xml COPYONLY)
endforeach()
add_executable(make_exodus_meshes exodus/make_exodus_meshes.cpp)
perinox_link_exodus(make_exodus_meshes)
target_include_directories(make_exodus_meshes PRIVATE ${CMAKE_CURRENT_SOURCE_DIR}/exodus)
add_test(NAME exodus_meshes_setup COMMAND make_exodus_meshes ${EXO_DIR})
set_tests_properties(exodus_meshes_setup PROPERTIES FIXTURES_SETUP exodus_meshes LABELS unit)
perinox_unit_test(exodus_meshes_setup peridigm_scene_values)  # the mesh writer and a scene's check: no driver

# perinox_exodus_run(NAME <name> SCENE <scene in EXO_DIR> NP <n> [SETS ...]): the driver on a
# test scene, which must converge; a fixture <name> for the comparisons.
function(perinox_exodus_run)
  cmake_parse_arguments(R "" "NAME;SCENE;NP" "SETS;CHECK" ${ARGN})
  perinox_mpi_command(mpi ${R_NP})
  set(cmd ${mpi} $<TARGET_FILE:perinox> run ${EXO_DIR}/${R_SCENE} --output ${PERINOX_TEST_OUT}/${R_NAME} --quiet)
  foreach(s ${R_SETS})
    list(APPEND cmd --set ${s})
  endforeach()
  add_test(NAME ${R_NAME} COMMAND ${Python3_EXECUTABLE} ${PERINOX_CHECK} --out ${PERINOX_TEST_OUT}/${R_NAME} --converged ${R_CHECK} -- ${cmd})
  set(labels unit)
  if(R_NP GREATER 1)
    list(APPEND labels mpi)
  endif()
  set_tests_properties(${R_NAME} PROPERTIES ENVIRONMENT "${PERINOX_TEST_ENV};PERINOX_PLOT_SCRIPT=" LABELS "${labels}"
    PROCESSORS ${R_NP} TIMEOUT 600 FIXTURES_REQUIRED exodus_meshes FIXTURES_SETUP ${R_NAME})
endfunction()

# Reading on 1 and 3 ranks: the bar (hex, two blocks, a node set by name, a side set by id, a block
# by name) and the 2D plate (quads, thickness, node sets by name and id, a block by id) from Exodus give the probes of the same scenes on the
# closed-form particle files, to 1e-12 (the particles agree to round-off: the meshes' coordinates
# are multiples of 0.25 and 0.1, the volumes sums of 8 or 4 quadrature terms), and the 3-rank
# runs the 1-rank ones to 1e-10 (the rank-independence bound of mpi_cantilever_compare).
foreach(case bar quad)
  perinox_exodus_run(NAME exodus_${case}_points SCENE ${case}_points.xml NP 1)
  foreach(np 1 3)
    perinox_exodus_run(NAME exodus_${case}_np${np} SCENE ${case}_exodus.xml NP ${np} CHECK --partition RCB --distributed)
  endforeach()
  add_test(NAME exodus_${case}_equals_points COMMAND ${Python3_EXECUTABLE} ${CMAKE_CURRENT_SOURCE_DIR}/compare_runs.py
    --rtol 1e-12 ${PERINOX_TEST_OUT}/exodus_${case}_points ${PERINOX_TEST_OUT}/exodus_${case}_np1)
  set_tests_properties(exodus_${case}_equals_points PROPERTIES LABELS unit
    FIXTURES_REQUIRED "exodus_${case}_points;exodus_${case}_np1")
  add_test(NAME exodus_${case}_ranks_compare COMMAND ${Python3_EXECUTABLE} ${CMAKE_CURRENT_SOURCE_DIR}/compare_runs.py
    --rtol 1e-10 ${PERINOX_TEST_OUT}/exodus_${case}_np1 ${PERINOX_TEST_OUT}/exodus_${case}_np3)
  set_tests_properties(exodus_${case}_ranks_compare PROPERTIES LABELS mpi
    FIXTURES_REQUIRED "exodus_${case}_np1;exodus_${case}_np3")
endforeach()

# The runs above are built distributed (the default: each rank reads its range of the elements,
# docs/exodus.md); built replicated (every rank reads the whole mesh) on 1 and 3 ranks, RCB and
# slabs, they give the same probes to 1e-10; and with slabs built distributed too.
foreach(case bar quad)
  foreach(run "replicated_np1;1;RCB;Replicated" "replicated_np3;3;RCB;Replicated" "replicated_slabs_np3;3;Slabs;Replicated"
              "slabs_np3;3;Slabs;Distributed")
    list(GET run 0 tag)
    list(GET run 1 np)
    list(GET run 2 method)
    list(GET run 3 construction)
    set(check --partition ${method})
    if(construction STREQUAL "Distributed")
      list(APPEND check --distributed)
    endif()
    perinox_exodus_run(NAME exodus_${case}_${tag} SCENE ${case}_exodus.xml NP ${np}
      SETS "Discretization/Construction=${construction}" "Discretization/Partition=${method}" CHECK ${check})
    add_test(NAME exodus_${case}_${tag}_compare COMMAND ${Python3_EXECUTABLE} ${CMAKE_CURRENT_SOURCE_DIR}/compare_runs.py
      --rtol 1e-10 ${PERINOX_TEST_OUT}/exodus_${case}_np1 ${PERINOX_TEST_OUT}/exodus_${case}_${tag})
    set_tests_properties(exodus_${case}_${tag}_compare PROPERTIES LABELS mpi
      FIXTURES_REQUIRED "exodus_${case}_np1;exodus_${case}_${tag}")
  endforeach()
endforeach()

# Bad meshes and mesh regions: one sentence naming the file (and block and element), exit code 2,
# nothing written.
function(perinox_bad_mesh name scene message)
  perinox_bad_input(${name} ${EXO_DIR}/${scene} "${message}" ${ARGN})
  set_tests_properties(badinput_${name} PROPERTIES FIXTURES_REQUIRED exodus_meshes)
endfunction()
set(MF "Discretization/Mesh File")
perinox_bad_mesh(exodus_inverted_hex bar_exodus.xml
  "inverted.e: element 2 of element block 1 ('left part') ('HEX8') is inverted or degenerate" --set "${MF}=inverted.e")
perinox_bad_mesh(exodus_flat_tet bar_exodus.xml
  "flat_tet.e: element 1 of element block 1 ('TETRA') has zero volume" --set "${MF}=flat_tet.e")
perinox_bad_mesh(exodus_pyramid bar_exodus.xml
  "pyramid.e: element block 1 has elements of type 'PYRAMID5' with 5 nodes, which perinox does not read" --set "${MF}=pyramid.e")
perinox_bad_mesh(exodus_no_blocks bar_exodus.xml "no_blocks.e: has no element blocks" --set "${MF}=no_blocks.e")
perinox_bad_mesh(exodus_sphere_no_volume bar_exodus.xml
  "sphere_no_volume.e: element block 1 has sphere elements with 1 attribute(s)" --set "${MF}=sphere_no_volume.e")
perinox_bad_mesh(exodus_not_exodus bar_exodus.xml "not_exodus.e: is not an Exodus II file" --set "${MF}=not_exodus.e")
perinox_bad_mesh(exodus_missing_file bar_exodus.xml "no_such_mesh.e: cannot open the Exodus mesh" --set "${MF}=no_such_mesh.e")
perinox_bad_mesh(exodus_2d_mesh_3d_scene bar_exodus.xml "quad.e: is a 2D mesh but the scene is 3D" --set "${MF}=quad.e")
perinox_bad_mesh(exodus_3d_mesh_2d_scene quad_exodus.xml
  "bar.e: element block 1 ('left part') has 3D elements ('HEX8') but the scene is 2D" --set "${MF}=bar.e")
perinox_bad_mesh(exodus_no_mesh_file bar_exodus.xml "'Discretization/Mesh File' is required when Type = Exodus" --set "${MF}=")
perinox_bad_mesh(exodus_mesh_file_for_particles bar_points.xml "'Discretization/Mesh File' is for Type = Exodus" --set "${MF}=bar.e")
perinox_bad_mesh(exodus_node_set_unknown bar_exodus.xml "region 'left': the mesh has no Node Set with name 'nope'"
  --set "Regions/left/Name=nope")
perinox_bad_mesh(exodus_node_set_id_unknown quad_exodus.xml "region 'right': the mesh has no Node Set with id 7"
  --set "Regions/right/Id=7")
perinox_bad_mesh(exodus_side_set_unknown bar_exodus.xml "region 'right': the mesh has no Side Set with id 2"
  --set "Regions/right/Id=2")
perinox_bad_mesh(exodus_name_and_id bar_exodus.xml "region 'left' (Type = Node Set) needs exactly one of Name and Id"
  --set "Regions/left/Id=1")
perinox_bad_mesh(exodus_node_set_on_particles bar_points.xml "region 'left' is a Node Set, which needs 'Discretization/Type' = Exodus"
  --set "Regions/left/Type=Node Set" --set "Regions/left/Name=left")
perinox_bad_mesh(exodus_block_unknown bar_exodus.xml "region 'second half': the mesh has no element block named 'middle'"
  --set "Regions/second half/Name=middle")
perinox_bad_mesh(block_empty bar_points.xml "region 'second half': no particle is in block 5"
  --set "Regions/second half/Id=5")

# Exodus results: the cantilever (xml/cantilever.xml, 4 load steps) with Output/Format = Both on
# 1 rank (direct) and 3 ranks (gmres-ilu, built replicated: the gather to rank 0 into one file;
# the default, one file per rank, is tested below), and Exodus alone; fields.e read back with the Exodus
# library (tests/exodus/check_exodus_output.cpp) must equal fields.csv at the last step and
# summary.json's tip probe at every step (on 3 ranks: the gather to rank 0 put every rank's
# particles in their place).
find_package(nlohmann_json REQUIRED)
add_executable(check_exodus_output exodus/check_exodus_output.cpp)
perinox_link_exodus(check_exodus_output)
target_link_libraries(check_exodus_output PRIVATE nlohmann_json::nlohmann_json)
foreach(np 1 3)
  set(preset direct)
  if(np GREATER 1)
    set(preset gmres-ilu)
  endif()
  foreach(format Both Exodus)
    set(name exodus_output_cantilever_${format}_np${np})
    perinox_run_test(NAME ${name} SCENE cantilever.xml NP ${np}
      SETS "Output/Format=${format}" "Solver/Load Steps=4" "Solver/Linear Solver Preset=${preset}" "Discretization/Construction=Replicated"
      CHECK --converged FIXTURE_SETUP ${name} LABELS unit)
    set(extra)
    if(format STREQUAL "Exodus")
      set(extra --no-vtu)
    endif()
    add_test(NAME ${name}_check COMMAND check_exodus_output ${PERINOX_TEST_OUT}/${name} --probe tip=tip --blocks 1 ${extra})
    set_tests_properties(${name}_check PROPERTIES LABELS unit FIXTURES_REQUIRED ${name})
  endforeach()
endforeach()
# Block structure kept (replicated on 3 ranks: one gathered file): the two-block bar's fields.e has blocks 1 and 2, and its spheres' volumes
# sum to the bar's volume, 4 x 1 x 1.
perinox_exodus_run(NAME exodus_output_bar SCENE bar_exodus.xml NP 3 SETS "Output/Format=Exodus" "Discretization/Construction=Replicated")
add_test(NAME exodus_output_bar_check COMMAND check_exodus_output ${PERINOX_TEST_OUT}/exodus_output_bar
  --probe "second half=second half" --blocks 1,2 --volume 4 --no-vtu)
set_tests_properties(exodus_output_bar_check PROPERTIES LABELS unit FIXTURES_REQUIRED exodus_output_bar)
# One file per rank when built distributed (the default) on several ranks (fields.e.3.0 ... fields.e.3.2, no
# rank holding the whole body): joined by their number maps they equal fields.csv and the probes,
# on the two-block bar (mesh read distributed) and the cantilever (a lattice, Format = Both).
perinox_exodus_run(NAME exodus_output_bar_distributed SCENE bar_exodus.xml NP 3 SETS "Output/Format=Exodus")
add_test(NAME exodus_output_bar_distributed_check COMMAND check_exodus_output ${PERINOX_TEST_OUT}/exodus_output_bar_distributed
  --probe "second half=second half" --blocks 1,2 --volume 4 --no-vtu --pieces 3)
set_tests_properties(exodus_output_bar_distributed_check PROPERTIES LABELS unit FIXTURES_REQUIRED exodus_output_bar_distributed)
perinox_run_test(NAME exodus_output_cantilever_distributed_np3 SCENE cantilever.xml NP 3
  SETS "Output/Format=Both" "Solver/Load Steps=4" "Solver/Linear Solver Preset=gmres-ilu"
  CHECK --converged FIXTURE_SETUP exodus_output_cantilever_distributed_np3 LABELS unit)
add_test(NAME exodus_output_cantilever_distributed_np3_check COMMAND check_exodus_output
  ${PERINOX_TEST_OUT}/exodus_output_cantilever_distributed_np3 --probe tip=tip --blocks 1 --pieces 3)
set_tests_properties(exodus_output_cantilever_distributed_np3_check PROPERTIES LABELS unit
  FIXTURES_REQUIRED exodus_output_cantilever_distributed_np3)
# A bad mesh read distributed is refused on every rank with the whole read's sentence (the bad
# element lies in rank 0's range, the missing node set is found by no rank).
function(perinox_bad_mesh_distributed name scene message)
  perinox_bad_input_distributed(${name} 3 ${EXO_DIR}/${scene} "${message}" ${ARGN})
  set_tests_properties(badinput_${name} PROPERTIES FIXTURES_REQUIRED exodus_meshes)
endfunction()
perinox_bad_mesh_distributed(distributed_exodus_inverted_hex bar_exodus.xml
  "inverted.e: element 2 of element block 1 ('left part') ('HEX8') is inverted or degenerate" --set "${MF}=inverted.e")
perinox_bad_mesh_distributed(distributed_exodus_missing_file bar_exodus.xml "no_such_mesh.e: cannot open the Exodus mesh"
  --set "${MF}=no_such_mesh.e")
perinox_bad_mesh_distributed(distributed_exodus_node_set_unknown bar_exodus.xml "region 'left': the mesh has no Node Set with name 'nope'"
  --set "Regions/left/Name=nope")
perinox_bad_mesh_distributed(distributed_exodus_output_bad_mesh bar_exodus.xml "inverted.e: element 2" --set "${MF}=inverted.e"
  --set "Output/Format=Exodus")

# Complete or absent: a bad mesh with Exodus output writes nothing.
perinox_bad_mesh(exodus_output_bad_mesh bar_exodus.xml "inverted.e: element 2" --set "${MF}=inverted.e" --set "Output/Format=Exodus")

# perinox_peridigm_scene(NAME DECK SCENE): peridigm_convert_NAME writes the scene DECK makes
# (perinox convert), and peridigm_convert_NAME_accepted has perinox build all of it (mesh, node
# sets, conditions, blocks, the rigid-body check), stopping before any solve at a --restart folder
# that does not exist.
function(perinox_peridigm_scene name deck scene)
  perinox_mpi_command(mpi1 1)
  add_test(NAME peridigm_convert_${name} COMMAND $<TARGET_FILE:perinox> convert ${deck} --out ${scene})
  set_tests_properties(peridigm_convert_${name} PROPERTIES ENVIRONMENT "${PERINOX_TEST_ENV}" LABELS unit
    FIXTURES_SETUP peridigm_${name})
  add_test(NAME peridigm_convert_${name}_accepted COMMAND ${Python3_EXECUTABLE} ${PERINOX_CHECK} --out ${PERINOX_TEST_OUT}/peridigm_${name}
    --exit-code 2 --message "no state.json there (not a checkpoint)" --no-output --
    ${mpi1} $<TARGET_FILE:perinox> run ${scene} --restart ${CMAKE_CURRENT_BINARY_DIR}/peridigm/no-such-checkpoint
    --output ${PERINOX_TEST_OUT}/peridigm_${name})
  set_tests_properties(peridigm_convert_${name}_accepted PROPERTIES ENVIRONMENT "${PERINOX_TEST_ENV}" LABELS unit
    FIXTURES_REQUIRED peridigm_${name})
endfunction()
# perinox convert on Peridigm's tensile deck: the scene holds the deck's numbers and perinox
# accepts it; a deck with two materials (tests/exodus/two_material_deck.yaml: the tensile test
# with a stiffer gauge block) becomes a scene with Blocks, accepted too; a deck it cannot
# translate is refused with one sentence.
if(EXISTS ${PERINOX_TENSILE_DIR}/tensile_test.yaml)
  set(PD_SCENE ${CMAKE_CURRENT_BINARY_DIR}/peridigm/tensile_test.xml)
  file(MAKE_DIRECTORY ${CMAKE_CURRENT_BINARY_DIR}/peridigm)
  perinox_peridigm_scene(to_scene ${PERINOX_TENSILE_DIR}/tensile_test.yaml ${PD_SCENE})
  add_test(NAME peridigm_scene_values COMMAND ${Python3_EXECUTABLE} ${CMAKE_CURRENT_SOURCE_DIR}/exodus/check_peridigm_scene.py ${PD_SCENE})
  set_tests_properties(peridigm_scene_values PROPERTIES LABELS unit FIXTURES_REQUIRED peridigm_to_scene)
  perinox_peridigm_scene(two_materials ${CMAKE_CURRENT_SOURCE_DIR}/exodus/two_material_deck.yaml
    ${CMAKE_CURRENT_BINARY_DIR}/peridigm/two_material_deck.xml)
  set_tests_properties(peridigm_convert_two_materials PROPERTIES PASS_REGULAR_EXPRESSION "3 blocks with their own materials")
endif()
add_test(NAME peridigm_convert_bad_deck COMMAND ${Python3_EXECUTABLE} ${CMAKE_CURRENT_SOURCE_DIR}/exodus/expect_refusal.py
  "is not of the form t (a + b x + c y + d z)" --
  $<TARGET_FILE:perinox> convert ${CMAKE_CURRENT_SOURCE_DIR}/exodus/bad_deck.yaml --out ${CMAKE_CURRENT_BINARY_DIR}/peridigm/bad_deck.xml)
set_tests_properties(peridigm_convert_bad_deck PROPERTIES ENVIRONMENT "${PERINOX_TEST_ENV}" LABELS "unit;badinput")

# Peridigm's tensile test run from its mesh and from its particle file (the same model): equal
# probes. Opt-in (-DPERINOX_LONG_TESTS=ON, label "long"): each run solves 34 275 unknowns with a
# horizon of 2.5 spacings, 45 s (mesh order) to over 10 minutes (the particle file's order, worse
# for ILU) of one core. Tolerance 1e-7: the particle file holds positions and volumes to 5e-10
# relative (10 printed digits), and each run's GMRES stops at 1e-12 of the residual in a different
# particle order.
option(PERINOX_LONG_TESTS "also register the long Exodus tests (the tensile test from mesh and particle file)" OFF)
if(PERINOX_LONG_TESTS AND EXISTS ${PERINOX_TENSILE_DIR}/tensile_test.g)
  foreach(scene tensile_exodus tensile_points)
    configure_file(${CMAKE_CURRENT_SOURCE_DIR}/exodus/${scene}.xml.in ${EXO_DIR}/${scene}.xml @ONLY)
    perinox_exodus_run(NAME exodus_${scene} SCENE ${scene}.xml NP 1)
    set_tests_properties(exodus_${scene} PROPERTIES LABELS long TIMEOUT 3600)
  endforeach()
  add_test(NAME exodus_tensile_mesh_equals_points COMMAND ${Python3_EXECUTABLE} ${CMAKE_CURRENT_SOURCE_DIR}/compare_runs.py
    --rtol 1e-7 ${PERINOX_TEST_OUT}/exodus_tensile_points ${PERINOX_TEST_OUT}/exodus_tensile_exodus)
  set_tests_properties(exodus_tensile_mesh_equals_points PROPERTIES LABELS long
    FIXTURES_REQUIRED "exodus_tensile_exodus;exodus_tensile_points")
endif()

# Round trip: the bar's fields.e read back as a mesh of sphere elements (volume = second
# attribute, the scene's regions as node sets, blocks block_1 and block_2) gives the bar's
# particles, so the run on it equals the run on bar.e (to 1e-12 as above).
perinox_exodus_run(NAME exodus_roundtrip_bar SCENE bar_exodus.xml NP 1
  SETS "Discretization/Mesh File=${PERINOX_TEST_OUT}/exodus_output_bar/fields.e" "Regions/right/Type=Node Set"
       "Regions/right/Id=-1" "Regions/right/Name=right" "Regions/second half/Name=block_2")
set_property(TEST exodus_roundtrip_bar APPEND PROPERTY FIXTURES_REQUIRED exodus_output_bar)
add_test(NAME exodus_roundtrip_bar_compare COMMAND ${Python3_EXECUTABLE} ${CMAKE_CURRENT_SOURCE_DIR}/compare_runs.py
  --rtol 1e-12 ${PERINOX_TEST_OUT}/exodus_bar_np1 ${PERINOX_TEST_OUT}/exodus_roundtrip_bar)
set_tests_properties(exodus_roundtrip_bar_compare PROPERTIES LABELS unit FIXTURES_REQUIRED "exodus_bar_np1;exodus_roundtrip_bar")

# Blocks with their own materials from a mesh: the two-material bar (tests/exodus/
# bimaterial_bar_exodus.xml, blocks by Name and Id) on 1 and 3 ranks against the closed form of
# two bars in series (tests/check_blocks_bar.py). Measured on 1 rank (40 x 4 x 4 hexahedra,
# delta = 2.015 h = 0.1, four particles across, so every particle is within a horizon of a
# lateral face; probes 2.25 horizons from the grips and the interface): block strains -1.8e-4 and
# +4.3e-3 of R / (E_k A) (bound 1e-2), interface
# displacement +2.6e-3 (bound 1e-2), reaction -6.3 % (bound 10 %: the grips' boundary layer, delta
# / L = 0.06 here); the 3-rank run equals the 1-rank one to 1e-10.
foreach(np 1 3)
  perinox_exodus_run(NAME blocks_exodus_bar_np${np} SCENE bimaterial_bar_exodus.xml NP ${np})
  add_test(NAME blocks_exodus_bar_np${np}_closed_form COMMAND ${Python3_EXECUTABLE} ${CMAKE_CURRENT_SOURCE_DIR}/check_blocks_bar.py
    ${PERINOX_TEST_OUT}/blocks_exodus_bar_np${np} --U 0.001 --A 0.04 --E1 1e9 --E2 4e9 --L1 0.8 --L2 0.8
    --probes a1=0.425 b1=0.775 a2=1.225 b2=1.575 --strain-rtol 1e-2 --interface-rtol 1e-2 --reaction-rtol 0.1)
  set_tests_properties(blocks_exodus_bar_np${np}_closed_form PROPERTIES LABELS "unit;verification" FIXTURES_REQUIRED blocks_exodus_bar_np${np})
endforeach()
perinox_exodus_run(NAME blocks_exodus_bar_replicated_np3 SCENE bimaterial_bar_exodus.xml NP 3
  SETS "Discretization/Construction=Replicated")
add_test(NAME blocks_exodus_bar_replicated_compare COMMAND ${Python3_EXECUTABLE} ${CMAKE_CURRENT_SOURCE_DIR}/compare_runs.py
  --rtol 1e-10 ${PERINOX_TEST_OUT}/blocks_exodus_bar_np1 ${PERINOX_TEST_OUT}/blocks_exodus_bar_replicated_np3)
set_tests_properties(blocks_exodus_bar_replicated_compare PROPERTIES LABELS mpi
  FIXTURES_REQUIRED "blocks_exodus_bar_np1;blocks_exodus_bar_replicated_np3")
add_test(NAME blocks_exodus_bar_ranks_compare COMMAND ${Python3_EXECUTABLE} ${CMAKE_CURRENT_SOURCE_DIR}/compare_runs.py
  --rtol 1e-10 ${PERINOX_TEST_OUT}/blocks_exodus_bar_np1 ${PERINOX_TEST_OUT}/blocks_exodus_bar_np3)
set_tests_properties(blocks_exodus_bar_ranks_compare PROPERTIES LABELS mpi FIXTURES_REQUIRED "blocks_exodus_bar_np1;blocks_exodus_bar_np3")
perinox_bad_mesh(blocks_exodus_name_unknown bimaterial_bar_exodus.xml "block 'soft': the mesh has no element block named 'middle'"
  --set "Blocks/soft/Name=middle")
perinox_bad_mesh(blocks_exodus_box bimaterial_bar_exodus.xml "'Blocks/stiff/Box Min' is for lattices"
  --set "Blocks/stiff/Box Min={1, 0, 0}" --set "Blocks/stiff/Box Max={2, 1, 1}")

# Nearest ties: (1.0, 0.25) is equally near the particles at (0.95, 0.25) and (1.05, 0.25) of the
# quad plate. Read from the Exodus mesh, from its particle file and from that file reversed, on
# 1 and 3 ranks, the 'Nearest' probe there picks the same particle (the smaller x), so the runs
# agree; with the old rule (the first particle in file order) the reversed file picked the other.
set(NEAREST_TIE "Regions/tie/Type=Nearest" "Regions/tie/Point={1.0, 0.25}" "Probes/tie/Region=tie")
add_test(NAME exodus_quad_points_reversed_setup COMMAND ${Python3_EXECUTABLE} ${CMAKE_CURRENT_SOURCE_DIR}/reverse_particle_file.py
  ${EXO_DIR}/quad_points.txt ${EXO_DIR}/quad_points_reversed.txt)
set_tests_properties(exodus_quad_points_reversed_setup PROPERTIES LABELS unit FIXTURES_REQUIRED exodus_meshes
  FIXTURES_SETUP quad_reversed)
perinox_exodus_run(NAME nearest_tie_exodus SCENE quad_exodus.xml NP 1 SETS ${NEAREST_TIE})
perinox_exodus_run(NAME nearest_tie_exodus_np3 SCENE quad_exodus.xml NP 3 SETS ${NEAREST_TIE})
perinox_exodus_run(NAME nearest_tie_points_reversed SCENE quad_points.xml NP 1
  SETS ${NEAREST_TIE} "Discretization/Particle File=quad_points_reversed.txt")
set_tests_properties(nearest_tie_points_reversed PROPERTIES FIXTURES_REQUIRED "exodus_meshes;quad_reversed")
foreach(other nearest_tie_exodus_np3 nearest_tie_points_reversed)
  add_test(NAME ${other}_compare COMMAND ${Python3_EXECUTABLE} ${CMAKE_CURRENT_SOURCE_DIR}/compare_runs.py
    --rtol 1e-10 ${PERINOX_TEST_OUT}/nearest_tie_exodus ${PERINOX_TEST_OUT}/${other})
  set_tests_properties(${other}_compare PROPERTIES LABELS unit FIXTURES_REQUIRED "nearest_tie_exodus;${other}")
endforeach()
