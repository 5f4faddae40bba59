# Dependencies, all from Debian 12 packages (scripts/setup installs them).
# Guarded so that a parent project can supply its own targets.
if(NOT TARGET TBB::tbb)
  # TBB's config must come before OpenVDB's FindTBB (see shared/DEPENDENCIES.md §2.5).
  find_package(TBB CONFIG REQUIRED COMPONENTS tbb tbbmalloc)
endif()
find_package(Threads REQUIRED)
find_package(ZLIB)   # optional: gzip (NIfTI .nii.gz, PNG pictures); io/formats and io/render use it when found

if(NORMALFLOW_WITH_CGAL AND NOT TARGET CGAL::CGAL)
  set(CGAL_DO_NOT_WARN_ABOUT_CMAKE_BUILD_TYPE TRUE)
  find_package(CGAL 5.5 CONFIG REQUIRED)
endif()

if(NORMALFLOW_WITH_OPENVDB AND NOT TARGET OpenVDB::openvdb)
  # Debian ships only a Find module, outside the default module path.
  # FindOpenVDB sets BUILD_SHARED_LIBS ON for the whole project when it finds a shared OpenVDB: keep ours.
  set(_nf_saved_module_path ${CMAKE_MODULE_PATH})
  set(_nf_saved_shared ${BUILD_SHARED_LIBS})
  file(GLOB _nf_vdb_dirs /usr/lib/*/cmake/OpenVDB /usr/lib/cmake/OpenVDB /usr/local/lib/cmake/OpenVDB)
  list(APPEND CMAKE_MODULE_PATH ${_nf_vdb_dirs})
  find_package(OpenVDB REQUIRED)
  set(CMAKE_MODULE_PATH ${_nf_saved_module_path})
  set(BUILD_SHARED_LIBS ${_nf_saved_shared})
endif()

if(NORMALFLOW_WITH_DRACO AND NOT TARGET draco::draco)
  find_package(draco CONFIG REQUIRED)
  find_package(Eigen3 3.3 CONFIG REQUIRED)   # draco's glTF headers include <Eigen/Geometry>
endif()

if(NORMALFLOW_WITH_OPENMESH AND NOT TARGET OpenMeshCore)
  find_package(OpenMesh CONFIG REQUIRED)     # no version file in Debian 12: no version argument
endif()

if(NORMALFLOW_WITH_MESHOPTIMIZER AND NOT TARGET meshoptimizer::meshoptimizer)
  find_package(meshoptimizer CONFIG REQUIRED)  # libmeshoptimizer-dev 0.18
endif()

if(NORMALFLOW_WITH_TETGEN AND NOT TARGET normalflow_tetgen_lib)
  # Debian's libtet1.5-dev has no CMake config or pkg-config file: wrap it in an imported target
  # that carries TETLIBRARY (tetgen.h must see it; the library was built with it).
  find_path(TETGEN_INCLUDE_DIR tetgen.h REQUIRED)
  find_library(TETGEN_LIBRARY tet REQUIRED)
  get_filename_component(TETGEN_LIBRARY_DIR "${TETGEN_LIBRARY}" DIRECTORY)
  add_library(normalflow_tetgen_lib UNKNOWN IMPORTED)
  set_target_properties(normalflow_tetgen_lib PROPERTIES
    IMPORTED_LOCATION "${TETGEN_LIBRARY}"
    INTERFACE_INCLUDE_DIRECTORIES "${TETGEN_INCLUDE_DIR}"
    INTERFACE_COMPILE_DEFINITIONS TETLIBRARY)
endif()
