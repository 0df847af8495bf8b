# install_test.cmake — ctest's install_and_use: installs the build tree into a fresh prefix,
# builds docs/library.md's C++ example (its ```cpp and ```cmake blocks, exactly as printed)
# against it as an outside project, and runs it, the installed CLI and the installed Python
# module on a generated shape.
#   cmake -DSOURCE_DIR=... -DBUILD_DIR=... -DWORK_DIR=... -DSHAPES=... -DPYTHON=... -P this
cmake_minimum_required(VERSION 3.18)

function(run)
  execute_process(COMMAND ${ARGN} RESULT_VARIABLE code OUTPUT_VARIABLE out ERROR_VARIABLE err)
  if(NOT code EQUAL 0)
    string(REPLACE ";" " " command "${ARGN}")
    message(FATAL_ERROR "failed (${code}): ${command}\n${out}\n${err}")
  endif()
  set(run_out "${out}" PARENT_SCOPE)
endfunction()

# The first fenced block of `lang` in docs/library.md.
function(doc_block lang var)
  file(READ ${SOURCE_DIR}/docs/library.md doc)
  string(FIND "${doc}" "```${lang}\n" start)
  if(start LESS 0)
    message(FATAL_ERROR "docs/library.md has no ```${lang} block")
  endif()
  string(LENGTH "```${lang}\n" fence)
  math(EXPR start "${start} + ${fence}")
  string(SUBSTRING "${doc}" ${start} -1 rest)
  string(FIND "${rest}" "```" end)
  string(SUBSTRING "${rest}" 0 ${end} block)
  set(${var} "${block}" PARENT_SCOPE)
endfunction()

set(prefix ${WORK_DIR}/prefix)
file(REMOVE_RECURSE ${WORK_DIR})
file(MAKE_DIRECTORY ${WORK_DIR}/app)
run(${CMAKE_COMMAND} --install ${BUILD_DIR} --prefix ${prefix})

# The installed headers must not pull in a private dependency.
file(GLOB_RECURSE headers ${prefix}/include/*.h)
foreach(h ${headers})
  file(STRINGS ${h} bad REGEX "#include <(openvdb|tbb|nlohmann|CLI)/")
  if(bad)
    message(FATAL_ERROR "${h} includes a private dependency: ${bad}")
  endif()
endforeach()

doc_block(cpp example)
doc_block(cmake lists)
file(WRITE ${WORK_DIR}/app/shell_file.cpp "${example}")
file(WRITE ${WORK_DIR}/app/CMakeLists.txt "${lists}")
run(${CMAKE_COMMAND} -S ${WORK_DIR}/app -B ${WORK_DIR}/app/build -G Ninja
    -DCMAKE_PREFIX_PATH=${prefix} -DCMAKE_BUILD_TYPE=Release)
run(${CMAKE_COMMAND} --build ${WORK_DIR}/app/build)

run(${SHAPES} horn -o ${WORK_DIR}/horn.obj)
run(${WORK_DIR}/app/build/shell_file ${WORK_DIR}/horn.obj ${WORK_DIR}/horn.vtu)
if(NOT run_out MATCHES "tets from 408 faces, coverage 0\\.[0-9]+")
  message(FATAL_ERROR "unexpected output of the example: ${run_out}")
endif()
if(NOT EXISTS ${WORK_DIR}/horn.vtu)
  message(FATAL_ERROR "the example wrote no horn.vtu")
endif()
# The installed executable finds the installed library (its RUNPATH), and writes the same shell.
run(${prefix}/bin/vdb_shell ${WORK_DIR}/horn.obj -r 64 -q -o ${WORK_DIR}/cli.vtu)
file(SHA256 ${WORK_DIR}/horn.vtu example_sha)
file(SHA256 ${WORK_DIR}/cli.vtu cli_sha)
if(NOT example_sha STREQUAL cli_sha)
  message(FATAL_ERROR "the example's shell differs from the installed CLI's")
endif()
# The installed CLI reads .vdb files through the installed reader program (libexec).
run(${prefix}/bin/vdb_shell ${WORK_DIR}/horn.obj -r 32 -q --grids ${WORK_DIR}/horn.vdb)
run(${prefix}/bin/vdb_shell ${WORK_DIR}/horn.vdb -r 32 -q -o ${WORK_DIR}/from_vdb.vtu)
if(NOT EXISTS ${WORK_DIR}/from_vdb.vtu)
  message(FATAL_ERROR "the installed CLI wrote no shell from a .vdb input")
endif()
# The installed Python module imports from the prefix alone.
if(PYTHON)
  file(GLOB_RECURSE module ${prefix}/lib/python3/dist-packages/vdb_shell*.so)
  if(NOT module)
    message(FATAL_ERROR "no Python module under ${prefix}/lib/python3/dist-packages")
  endif()
  # (newlines, not semicolons: CMake would split the argument there)
  run(${CMAKE_COMMAND} -E env PYTHONPATH=${prefix}/lib/python3/dist-packages ${PYTHON} -c
      "import vdb_shell\nv, f = vdb_shell.load_surface('${WORK_DIR}/horn.obj')\nprint(len(f))")
  if(NOT run_out MATCHES "^408")
    message(FATAL_ERROR "the installed Python module read ${run_out}")
  endif()
endif()
file(REMOVE_RECURSE ${WORK_DIR})
message(STATUS "install_and_use: installed, built and ran docs/library.md's example")
