// libFuzzer target: the input as a VTK XML .vtu file (the XML scanner, ascii DataArrays), loaded
// with sh_mesh_load and checked as fuzz_check.hpp says. Seeds: corpus/vtu/.
#include "fuzz_check.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    softhap_fuzz::check_file("input.vtu", data, size);
    return 0;
}
