# Small find module for OpenVDB 10 as Debian ships it (libopenvdb-dev).
#
# Debian's own FindOpenVDB.cmake needs Boost.Iostreams' CMake files and sets BUILD_SHARED_LIBS
# in the caller's scope; this one only looks for the header, the library and the headers the
# OpenVDB headers include (Imath, TBB, Boost). Defines the imported target OpenVDB::openvdb.

find_path(OpenVDB_INCLUDE_DIR openvdb/openvdb.h)
find_library(OpenVDB_LIBRARY NAMES openvdb)
find_path(OpenVDB_Imath_INCLUDE_DIR Imath/half.h)
find_path(OpenVDB_Boost_INCLUDE_DIR boost/any.hpp)

if(OpenVDB_INCLUDE_DIR AND EXISTS "${OpenVDB_INCLUDE_DIR}/openvdb/version.h")
  file(STRINGS "${OpenVDB_INCLUDE_DIR}/openvdb/version.h" _vdb_major
       REGEX "^#define OPENVDB_LIBRARY_MAJOR_VERSION_NUMBER +[0-9]+")
  file(STRINGS "${OpenVDB_INCLUDE_DIR}/openvdb/version.h" _vdb_minor
       REGEX "^#define OPENVDB_LIBRARY_MINOR_VERSION_NUMBER +[0-9]+")
  string(REGEX MATCH "[0-9]+$" _vdb_major "${_vdb_major}")
  string(REGEX MATCH "[0-9]+$" _vdb_minor "${_vdb_minor}")
  set(OpenVDB_VERSION "${_vdb_major}.${_vdb_minor}")
endif()

include(FindPackageHandleStandardArgs)
find_package_handle_standard_args(OpenVDB
  REQUIRED_VARS OpenVDB_LIBRARY OpenVDB_INCLUDE_DIR OpenVDB_Imath_INCLUDE_DIR
                OpenVDB_Boost_INCLUDE_DIR
  VERSION_VAR OpenVDB_VERSION
  REASON_FAILURE_MESSAGE
    "install the Debian packages libopenvdb-dev and libboost-dev (scripts/install-deps.sh)")

if(OpenVDB_FOUND AND NOT TARGET OpenVDB::openvdb)
  find_package(TBB REQUIRED)
  add_library(OpenVDB::openvdb UNKNOWN IMPORTED)
  set_target_properties(OpenVDB::openvdb PROPERTIES
    IMPORTED_LOCATION "${OpenVDB_LIBRARY}"
    INTERFACE_INCLUDE_DIRECTORIES
      "${OpenVDB_INCLUDE_DIR};${OpenVDB_Imath_INCLUDE_DIR};${OpenVDB_Boost_INCLUDE_DIR}"
    INTERFACE_LINK_LIBRARIES TBB::tbb)
endif()
mark_as_advanced(OpenVDB_INCLUDE_DIR OpenVDB_LIBRARY OpenVDB_Imath_INCLUDE_DIR
                 OpenVDB_Boost_INCLUDE_DIR)
