// load_mesh_file: reads the file and hands its text to the reader its extension names.
#include "mesh/io/mesh_io.hpp"
#include "mesh/io/text_reader.hpp"

namespace sh {
namespace {

enum class Format { Gmsh, VtkLegacy, Vtu, Tetgen, Surface, Unknown };

// The file's extension without the dot ("" if none).
std::string_view extension_of(const std::string& path) {
    const size_t dot = path.find_last_of('.');
    const size_t slash = path.find_last_of("/\\");
    if (dot == std::string::npos || (slash != std::string::npos && dot < slash)) return {};
    return std::string_view(path).substr(dot + 1);
}

Format format_of(std::string_view ext) {
    if (equals_nocase(ext, "msh")) return Format::Gmsh;
    if (equals_nocase(ext, "vtk")) return Format::VtkLegacy;
    if (equals_nocase(ext, "vtu")) return Format::Vtu;
    if (equals_nocase(ext, "node") || equals_nocase(ext, "ele")) return Format::Tetgen;
    for (const char* surface : {"obj", "stl", "ply", "off"})
        if (equals_nocase(ext, surface)) return Format::Surface;
    return Format::Unknown;
}

}  // namespace

MeshData load_mesh_file(const std::string& path) {
    const vec<char> bytes = read_text_file(path);  // SH_ERR_IO first: a missing file is a missing file
    const std::string_view text(bytes.data(), bytes.size());
    const std::string_view ext = extension_of(path);
    const Format kind = format_of(ext);
    if (kind == Format::Surface)
        throw Error(SH_ERR_UNSUPPORTED,
                    format("%s: .%s is a surface format (triangles), not a tetrahedral mesh; tetrahedralise it "
                           "first (e.g. with TetGen or Gmsh)", path.c_str(), printable(ext).c_str()));
    if (kind == Format::Unknown)
        throw Error(SH_ERR_UNSUPPORTED,
                    format("%s: %s%s%s is not a mesh format softhap reads (supported: .msh, .vtk, .vtu, .node/.ele)",
                           path.c_str(), ext.empty() ? "a file without extension" : "extension '",
                           printable(ext).c_str(), ext.empty() ? "" : "'"));
    if (text.find_first_not_of(" \t\r\n") == std::string_view::npos)
        throw Error(SH_ERR_PARSE, format("%s:1: the file is empty", path.c_str()));
    switch (kind) {
        case Format::Gmsh: return read_gmsh(path, text);
        case Format::VtkLegacy: return read_vtk_legacy(path, text);
        case Format::Vtu: return read_vtu(path, text);
        default: return read_tetgen(path, text);
    }
}

}  // namespace sh
