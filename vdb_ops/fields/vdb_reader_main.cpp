// vdb_shell_vdb_reader — reads a .vdb file for read_vdb_isolated() (fields_internal.h) in a
// process of its own, so that a corrupt file can only take this process down.
#include "vdb_ops/fields/fields_internal.h"

int main(int argc, char** argv) { return vdb_shell::fields_detail::vdb_reader_main(argc, argv); }

#if defined(__has_feature)
#if __has_feature(address_sanitizer)
// Built with the sanitizers, the reader reports what a corrupt file makes OpenVDB do to a stderr
// that is /dev/null, and its caller only sees that it ended. Symbolizing that report starts
// llvm-symbolizer, which cannot map memory inside the reader's allowance once the file's claims
// have used it up; the reader then waited for it forever (bloscfromstream-overflow, at 128 MiB).
// Unsymbolized, the report ends the reader at once. ASAN_OPTIONS and UBSAN_OPTIONS still apply
// on top of these.
extern "C" const char* __asan_default_options() { return "symbolize=0"; }
extern "C" const char* __ubsan_default_options() { return "symbolize=0"; }
#endif
#endif
