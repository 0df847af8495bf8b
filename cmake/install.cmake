# Installation: `cmake --install build --prefix P` puts the library, its headers, both
# executables, the programs of libexec/vdb_shell, the Python module and a CMake package under P,
# so that an outside project can
#   find_package(vdb_shell REQUIRED)
#   target_link_libraries(app PRIVATE vdb_shell::vdb_shell)
# The library links OpenVDB and TBB privately: the package needs none of them.
include(CMakePackageConfigHelpers)

set(VDB_SHELL_INSTALL_CMAKEDIR ${CMAKE_INSTALL_LIBDIR}/cmake/vdb_shell)
# The executables find libvdb_shell.so from where they are, wherever the tree is installed.
set_target_properties(vdb_shell_shapes PROPERTIES
  INSTALL_RPATH "$ORIGIN/../${CMAKE_INSTALL_LIBDIR}")
file(RELATIVE_PATH _vdb_shell_libdir_from_program "/prefix/${CMAKE_INSTALL_LIBEXECDIR}/vdb_shell"
     "/prefix/${CMAKE_INSTALL_LIBDIR}")
set_target_properties(vdb_shell_program PROPERTIES
  INSTALL_RPATH "$ORIGIN/${_vdb_shell_libdir_from_program}")

install(TARGETS vdb_shell_lib EXPORT vdb_shell_targets
  LIBRARY DESTINATION ${CMAKE_INSTALL_LIBDIR}
  RUNTIME DESTINATION ${CMAKE_INSTALL_BINDIR}
  INCLUDES DESTINATION ${CMAKE_INSTALL_INCLUDEDIR})
install(TARGETS vdb_shell vdb_shell_shapes RUNTIME DESTINATION ${CMAKE_INSTALL_BINDIR})
# The program the command starts (cli/CMakeLists.txt) and the .vdb reader program, where the
# library looks for it (vdb_ops/CMakeLists.txt).
install(TARGETS vdb_shell_program vdb_shell_vdb_reader
  RUNTIME DESTINATION ${CMAKE_INSTALL_LIBEXECDIR}/vdb_shell)

# The public header and the headers of the types it hands out (none includes a dependency's).
install(FILES include/vdb_shell/vdb_shell.h DESTINATION ${CMAKE_INSTALL_INCLUDEDIR}/vdb_shell)
foreach(header
    base/errors.h base/run_control.h base/surface_mesh.h base/tet_mesh.h base/vec3.h
    read/load_surface.h read/polygon_soup.h read/zero_area.h trace/field_sampler.h
    trace/trace.h inner/inner.h validity/optimize.h validity/search.h validity/shell_checks.h
    assemble/assemble.h assemble/quality.h)
  get_filename_component(folder ${header} DIRECTORY)
  install(FILES core/${header} DESTINATION ${CMAKE_INSTALL_INCLUDEDIR}/vdb_shell/core/${folder})
endforeach()
install(FILES vdb_ops/fields.h vdb_ops/repair.h DESTINATION ${CMAKE_INSTALL_INCLUDEDIR}/vdb_shell/vdb_ops)

install(EXPORT vdb_shell_targets NAMESPACE vdb_shell:: FILE vdb_shell-targets.cmake
  DESTINATION ${VDB_SHELL_INSTALL_CMAKEDIR})
configure_package_config_file(${CMAKE_CURRENT_LIST_DIR}/vdb_shell-config.cmake.in
  ${CMAKE_CURRENT_BINARY_DIR}/vdb_shell-config.cmake
  INSTALL_DESTINATION ${VDB_SHELL_INSTALL_CMAKEDIR})
write_basic_package_version_file(${CMAKE_CURRENT_BINARY_DIR}/vdb_shell-config-version.cmake
  COMPATIBILITY SameMinorVersion)
install(FILES ${CMAKE_CURRENT_BINARY_DIR}/vdb_shell-config.cmake
  ${CMAKE_CURRENT_BINARY_DIR}/vdb_shell-config-version.cmake
  DESTINATION ${VDB_SHELL_INSTALL_CMAKEDIR})
