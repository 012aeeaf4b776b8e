// Mesh file readers and writers. One file per format; load_mesh_file dispatches.
#pragma once

#include "mesh/tet_mesh.hpp"

#include <cstdint>
#include <string>
#include <string_view>

namespace sh {

/// Reads a tetrahedral mesh file, choosing the format by extension (and content where the
/// extension is ambiguous): .msh (Gmsh 1, 2.2, 4.1 ASCII), .vtk (legacy ASCII
/// UNSTRUCTURED_GRID), .vtu (VTK XML, ascii data), .node/.ele (TetGen). Non-tet elements are
/// skipped and counted. Throws SH_ERR_IO (cannot open/read), SH_ERR_PARSE ("file:line: what"),
/// SH_ERR_UNSUPPORTED (binary or unknown format). Does not validate geometry.
MeshData load_mesh_file(const std::string& path);

/// Per-format readers behind load_mesh_file. text is the file's content; path names it in
/// messages. Same errors as load_mesh_file.

/// Gmsh .msh: version 1 ($NOD/$ELM), 2.x ASCII and 4.1 ASCII; node tags map to file order.
MeshData read_gmsh(const std::string& path, std::string_view text);

/// Legacy VTK ASCII UNSTRUCTURED_GRID (classic CELLS and the 5.1 OFFSETS/CONNECTIVITY form).
MeshData read_vtk_legacy(const std::string& path, std::string_view text);

/// VTK XML UnstructuredGrid with ascii DataArrays; header counts must match the data.
MeshData read_vtu(const std::string& path, std::string_view text);

/// TetGen .node + .ele: path is either file (text its content); the other is read beside it.
MeshData read_tetgen(const std::string& path, std::string_view text);

/// What write_vtu writes: points and cells of one kind, plus optional per-point 3-vectors.
struct VtuFrame {
    const double* points = nullptr;   ///< 3 per point
    int64_t point_count = 0;
    const int32_t* cells = nullptr;   ///< nodes_per_cell per cell
    int64_t cell_count = 0;
    int nodes_per_cell = 4;           ///< 4: VTK_TETRA (10), 3: VTK_TRIANGLE (5), 2: VTK_LINE (3)
    const double* point_vectors = nullptr;  ///< optional 3 per point
    const char* point_vectors_name = nullptr;
};

/// Writes frame as an ASCII VTK XML UnstructuredGrid file. Throws SH_ERR_IO on failure.
void write_vtu(const std::string& path, const VtuFrame& frame);

}  // namespace sh
