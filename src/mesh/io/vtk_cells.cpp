#include "mesh/io/vtk_cells.hpp"

#include <limits>

namespace sh {

void append_vtk_tets(const VtkCells& cells, const TextReader& reader, MeshData& mesh) {
    const size_t cell_count = cells.offsets.size();
    const int64_t size = static_cast<int64_t>(cells.connectivity.size());
    if (cells.types.size() != cell_count)
        reader.fail_at(cells.types_line, format("%zu cell types for %zu cells", cells.types.size(), cell_count));
    if (cell_count > 0 && cells.offsets.back() != size)
        reader.fail_at(cells.offsets_line,
                       format("the last cell ends at offset %lld but the connectivity holds %lld values",
                              static_cast<long long>(cells.offsets.back()), static_cast<long long>(size)));
    size_t tets = 0;
    for (const int64_t type : cells.types) tets += (type == kVtkTetra) ? 1 : 0;
    mesh.tets.reserve(mesh.tets.size() + 4 * tets);
    mesh.tet_lines.reserve(mesh.tet_lines.size() + tets);

    int64_t start = 0;
    for (size_t c = 0; c < cell_count; ++c) {
        const int64_t end = cells.offsets[c];
        if (end < start || end > size)
            reader.fail_at(cells.offsets_line,
                           format("offset %lld of cell %zu is outside [%lld, %lld]", static_cast<long long>(end),
                                  c, static_cast<long long>(start), static_cast<long long>(size)));
        if (cells.types[c] != kVtkTetra) {
            ++mesh.skipped_elements;
        } else {
            const int line = start < end ? cells.connectivity_lines[static_cast<size_t>(start)] : cells.offsets_line;
            if (end - start != 4)
                reader.fail_at(line, format("cell %zu is a VTK_TETRA with %lld nodes, expected 4", c,
                                            static_cast<long long>(end - start)));
            for (int64_t i = start; i < end; ++i) {
                const int64_t node = cells.connectivity[static_cast<size_t>(i)];
                if (node < std::numeric_limits<int32_t>::min() || node > std::numeric_limits<int32_t>::max())
                    reader.fail_at(line, format("cell %zu: node index %lld does not fit in 32 bits", c,
                                                static_cast<long long>(node)));
                mesh.tets.push_back(static_cast<int32_t>(node));
            }
            mesh.tet_lines.push_back(line);
        }
        start = end;
    }
}

}  // namespace sh
