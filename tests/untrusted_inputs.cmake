# Untrusted files stay harmless: meshes, particle files and checkpoints that are damaged, crafted
# or impossible are refused with one sentence (exit 2, nothing written) on 1 rank and, where only
# some ranks see the defect, on 2 and 3 ranks within seconds (a rank refusing alone used to leave
# the others waiting forever). Included from tests/CMakeLists.txt after exodus/exodus_tests.cmake
# (perinox_bad_mesh, perinox_bad_mesh_distributed, EXO_DIR, MF).

# Exodus: an element type name longer than Exodus' 32 characters (the library copies it whole
# into a fixed buffer: bad_alloc at 40 characters, stack smashing at 200, a segmentation fault at
# 5 000 before the reader measured it), on 1 and 3 ranks.
foreach(length 40 200 5000)
  perinox_bad_mesh(exodus_long_type_${length} bar_exodus.xml "long_type_${length}.e: element block 1 ('left part') has an element type name of"
    --set "${MF}=long_type_${length}.e")
endforeach()
perinox_bad_mesh_distributed(distributed_exodus_long_type bar_exodus.xml "long_type_5000.e: element block 1 ('left part') has an element type name of"
  --set "${MF}=long_type_5000.e")
perinox_bad_mesh(exodus_duplicate_element bar_exodus.xml "particles 0 and 16 coincide" --set "${MF}=duplicate_element.e"
  --set "Regions/second half/Name=left part")
perinox_bad_mesh(exodus_spheres_one_node bar_exodus.xml "particles 1 and 45 coincide" --set "${MF}=spheres_one_node.e"
  --set "Regions/right/Type=Node Set" --set "Regions/right/Id=-1" --set "Regions/right/Name=right" --set "Regions/second half/Name=balls")
perinox_bad_mesh(exodus_negative_block bar_exodus.xml "negative_block.e: has element block id -3 (block ids must be 0 or more" --set "${MF}=negative_block.e")
# An element far from the others has no neighbour: one sentence on every rank count, either
# construction.
perinox_bad_mesh(exodus_stray_element bar_exodus.xml "particle 256 has a singular shape tensor" --set "${MF}=stray_element.e")
foreach(np 2 3)
  perinox_bad_input_distributed(exodus_stray_element_np${np} ${np} ${EXO_DIR}/bar_exodus.xml "particle 256 has a singular shape tensor"
    --set "${MF}=stray_element.e")
  set_tests_properties(badinput_exodus_stray_element_np${np} PROPERTIES FIXTURES_REQUIRED exodus_meshes TIMEOUT 60)
  perinox_bad_input_distributed(exodus_stray_element_replicated_np${np} ${np} ${EXO_DIR}/bar_exodus.xml "particle 256 has a singular shape tensor"
    --set "${MF}=stray_element.e" --set Discretization/Construction=Replicated)
  set_tests_properties(badinput_exodus_stray_element_replicated_np${np} PROPERTIES FIXTURES_REQUIRED exodus_meshes TIMEOUT 60)
endforeach()

# Particle files (tests/bad_input/make_bad_particle_files.py writes them).
set(PF_DIR ${PERINOX_TEST_OUT}/bad_particle_files)
add_test(NAME bad_particle_files_setup COMMAND ${Python3_EXECUTABLE} ${CMAKE_CURRENT_SOURCE_DIR}/bad_input/make_bad_particle_files.py ${PF_DIR})
set_tests_properties(bad_particle_files_setup PROPERTIES LABELS "unit;badinput" FIXTURES_SETUP bad_particle_files)
perinox_unit_test(bad_particle_files_setup)
set(PF_SCENE ${CMAKE_CURRENT_SOURCE_DIR}/scenes/tension_block_file.xml)
set(PF "Discretization/Particle File")
foreach(case "stray;particle 220 has a singular shape tensor"
             "repeated;particles 4 and 220 coincide"
             "hex;:8: '0x1p-5' is not a number"
             "tiny_volume;is below 1e-150 (products of two volumes would underflow)"
             "negative_block;:8: block id must be an integer of 0 or more (got -2)"
             "fifo;fifo.txt: is not a regular file"
             "folder;folder.txt: is a folder, not a particle file")
  list(GET case 0 name)
  list(GET case 1 message)
  perinox_bad_input(particle_file_${name} ${PF_SCENE} "${message}" --set "${PF}=${PF_DIR}/${name}.txt")
  set_tests_properties(badinput_particle_file_${name} PROPERTIES FIXTURES_REQUIRED bad_particle_files TIMEOUT 60)
endforeach()
foreach(case "stray;particle 220 has a singular shape tensor" "repeated;particles 4 and 220 coincide" "fifo;fifo.txt: is not a regular file")
  list(GET case 0 name)
  list(GET case 1 message)
  foreach(np 2 3)
    perinox_bad_input_distributed(particle_file_${name}_np${np} ${np} ${PF_SCENE} "${message}" --set "${PF}=${PF_DIR}/${name}.txt")
    set_tests_properties(badinput_particle_file_${name}_np${np} PROPERTIES FIXTURES_REQUIRED bad_particle_files TIMEOUT 60)
    perinox_bad_input_distributed(particle_file_${name}_replicated_np${np} ${np} ${PF_SCENE} "${message}"
      --set "${PF}=${PF_DIR}/${name}.txt" --set Discretization/Construction=Replicated)
    set_tests_properties(badinput_particle_file_${name}_replicated_np${np} PROPERTIES FIXTURES_REQUIRED bad_particle_files TIMEOUT 60)
  endforeach()
endforeach()

# Checkpoints checked as data and tied to their mesh by content (tests/exodus/check_checkpoint_inputs.py).
perinox_mpi_command(mpi_ck 1)
string(REPLACE ";" " " MPI_CK "${mpi_ck}")
add_test(NAME badinput_checkpoint_inputs COMMAND ${Python3_EXECUTABLE} ${CMAKE_CURRENT_SOURCE_DIR}/exodus/check_checkpoint_inputs.py
  --perinox $<TARGET_FILE:perinox> --meshes ${EXO_DIR} --work ${PERINOX_TEST_OUT}/checkpoint_inputs --mpi "${MPI_CK}")
set_tests_properties(badinput_checkpoint_inputs PROPERTIES ENVIRONMENT "${PERINOX_TEST_ENV};PERINOX_PLOT_SCRIPT=" LABELS "unit;badinput"
  FIXTURES_REQUIRED exodus_meshes TIMEOUT 300)

# netCDF-4 (HDF5) Exodus files are read as classic ones are: the bar from bar_netcdf4.e equals the
# bar from bar.e (the same particles, to 1e-12). Half of that file is refused with perinox's one
# sentence (the Exodus library used to print three lines of its own, blaming netCDF-4 support).
perinox_exodus_run(NAME exodus_bar_netcdf4 SCENE bar_exodus.xml NP 1 SETS "Discretization/Mesh File=bar_netcdf4.e")
add_test(NAME exodus_bar_netcdf4_compare COMMAND ${Python3_EXECUTABLE} ${CMAKE_CURRENT_SOURCE_DIR}/compare_runs.py
  --rtol 1e-12 ${PERINOX_TEST_OUT}/exodus_bar_np1 ${PERINOX_TEST_OUT}/exodus_bar_netcdf4)
set_tests_properties(exodus_bar_netcdf4_compare PROPERTIES LABELS unit FIXTURES_REQUIRED "exodus_bar_np1;exodus_bar_netcdf4")
perinox_bad_mesh(exodus_netcdf4_cut bar_exodus.xml "bar_netcdf4_cut.e: is an HDF5 file that netCDF cannot read" --set "${MF}=bar_netcdf4_cut.e")

# A classic file whose header declares more than the file holds is refused before the netCDF
# library allocates it (a damaged count in a 2 kB file made it touch 3.5 GB): the bar cut short.
perinox_bad_mesh(exodus_classic_cut bar_exodus.xml "bar_cut.e: is truncated" --set "${MF}=bar_cut.e")

# The fuzz test of the files, on 2 ranks: damaged particle files, meshes and checkpoints, each
# case exit 0, 2 or 3 with the one-sentence contract, none longer than 60 s (a hang fails it).
add_test(NAME fuzz_inputs COMMAND ${Python3_EXECUTABLE} ${CMAKE_CURRENT_SOURCE_DIR}/fuzz_inputs.py
  --perinox $<TARGET_FILE:perinox> --meshes ${EXO_DIR} --workdir ${PERINOX_TEST_OUT}/fuzz_inputs --seed 1 --cases 60 --ranks 2)
set_tests_properties(fuzz_inputs PROPERTIES ENVIRONMENT "${PERINOX_TEST_ENV}" LABELS "unit;badinput;mpi" PROCESSORS 2
  FIXTURES_REQUIRED exodus_meshes TIMEOUT 1200)
