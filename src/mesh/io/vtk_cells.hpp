// VTK cell arrays (shared by the legacy .vtk and the XML .vtu readers): offsets, connectivity
// and cell types, turned into tets. Only VTK_TETRA (10) cells are kept; others are counted.
#pragma once

#include "mesh/io/text_reader.hpp"
#include "mesh/tet_mesh.hpp"

#include <cstdint>

namespace sh {

/// VTK's linear tetrahedron cell type.
constexpr int64_t kVtkTetra = 10;

/// Cells as VTK stores them; every array is filled by the format's reader.
struct VtkCells {
    vec<int64_t> offsets;           ///< end of each cell in connectivity (no leading 0)
    vec<int64_t> connectivity;      ///< node indices of all cells, back to back
    vec<int32_t> connectivity_lines;///< file line of each connectivity value
    vec<int64_t> types;             ///< VTK cell type of each cell
    int offsets_line = 0;           ///< where the offsets start (for messages)
    int types_line = 0;             ///< where the types start (for messages)
};

/// Appends the VTK_TETRA cells of cells to mesh (tet_lines from connectivity_lines) and counts
/// the other cells in mesh.skipped_elements. Fails (SH_ERR_PARSE through reader) when the arrays
/// disagree: offsets not increasing or beyond the connectivity, a type count different from
/// the cell count, or a VTK_TETRA cell without exactly 4 nodes.
void append_vtk_tets(const VtkCells& cells, const TextReader& reader, MeshData& mesh);

}  // namespace sh
