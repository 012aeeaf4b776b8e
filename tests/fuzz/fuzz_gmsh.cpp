// libFuzzer target: the input as a Gmsh .msh file (versions 1, 2.2 and 4.1 ASCII), loaded with
// sh_mesh_load and checked as fuzz_check.hpp says. Seeds: corpus/gmsh/.
#include "fuzz_check.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    softhap_fuzz::check_file("input.msh", data, size);
    return 0;
}
