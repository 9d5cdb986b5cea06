# Trilinos in this Debian build is MPI-enabled; compile with the MPI wrapper unless a compiler is
# given. Include before project(): perinox's top level and examples/CMakeLists.txt do.
if(NOT CMAKE_CXX_COMPILER)
  find_program(PERINOX_MPICXX mpicxx)
  if(PERINOX_MPICXX)
    set(CMAKE_CXX_COMPILER ${PERINOX_MPICXX})
  endif()
endif()
