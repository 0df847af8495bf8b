// vdb_shell_vdb_reader — reads a .vdb file for read_vdb_isolated() (fields_internal.h) in a
// process of its own, so that a corrupt file can only take this process down.
#include "vdb_ops/fields/fields_internal.h"

int main(int argc, char** argv) { return vdb_shell::fields_detail::vdb_reader_main(argc, argv); }
