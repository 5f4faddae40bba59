# Dependencies, all from Debian 12 packages (scripts/setup installs them).
# Guarded so that a parent project can supply its own targets.
if(NOT TARGET TBB::tbb)
  # TBB's config must come before OpenVDB's FindTBB (see shared/DEPENDENCIES.md §2.5).
  find_package(TBB CONFIG REQUIRED COMPONENTS tbb tbbmalloc)
endif()
find_package(Threads REQUIRED)

if(NORMALFLOW_WITH_CGAL AND NOT TARGET CGAL::CGAL)
  set(CGAL_DO_NOT_WARN_ABOUT_CMAKE_BUILD_TYPE TRUE)
  find_package(CGAL 5.5 CONFIG REQUIRED)
endif()

if(NORMALFLOW_WITH_OPENVDB AND NOT TARGET OpenVDB::openvdb)
  # Debian ships only a Find module, outside the default module path.
  set(_nf_saved_module_path ${CMAKE_MODULE_PATH})
  file(GLOB _nf_vdb_dirs /usr/lib/*/cmake/OpenVDB /usr/lib/cmake/OpenVDB /usr/local/lib/cmake/OpenVDB)
  list(APPEND CMAKE_MODULE_PATH ${_nf_vdb_dirs})
  find_package(OpenVDB REQUIRED)
  set(CMAKE_MODULE_PATH ${_nf_saved_module_path})
endif()

if(NORMALFLOW_WITH_DRACO AND NOT TARGET draco::draco)
  find_package(draco CONFIG REQUIRED)
  find_package(Eigen3 3.3 CONFIG REQUIRED)   # draco's glTF headers include <Eigen/Geometry>
endif()
