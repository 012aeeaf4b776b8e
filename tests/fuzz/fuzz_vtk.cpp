// libFuzzer target: the input as a legacy VTK file (ASCII UNSTRUCTURED_GRID, classic and 5.1
// cells), loaded with sh_mesh_load and checked as fuzz_check.hpp says. Seeds: corpus/vtk/.
#include "fuzz_check.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    softhap_fuzz::check_file("input.vtk", data, size);
    return 0;
}
