// write_vtu: ASCII VTK XML UnstructuredGrid. Doubles are written as %.17g (std::to_chars, so the
// C locale of the host does not matter) and read back bit for bit.
#include "mesh/io/mesh_io.hpp"

#include "core/error.hpp"

#include <cerrno>
#include <charconv>
#include <cstdio>
#include <cstring>

namespace sh {
namespace {

// Buffered writer over a FILE*; every failure is SH_ERR_IO naming the file, and a file that
// could not be completed is removed.
class VtuOut {
public:
    explicit VtuOut(const std::string& path) : path_(path), file_(std::fopen(path.c_str(), "wb")) {
        if (!file_) throw Error(SH_ERR_IO, format("cannot open '%s' for writing: %s", path.c_str(), std::strerror(errno)));
    }

    ~VtuOut() {
        if (file_) {  // not closed: an exception is on its way, drop the partial file
            std::fclose(file_);
            std::remove(path_.c_str());
        }
    }

    void text(const char* s) { append(s, std::strlen(s)); }

    void real(double value) {
        char buf[40];
        const auto result = std::to_chars(buf, buf + sizeof buf, value, std::chars_format::general, 17);
        append(buf, static_cast<size_t>(result.ptr - buf));
    }

    void integer(int64_t value) {
        char buf[24];
        const auto result = std::to_chars(buf, buf + sizeof buf, value);
        append(buf, static_cast<size_t>(result.ptr - buf));
    }

    // Flushes and closes; throws SH_ERR_IO if anything failed to reach the file.
    void close() {
        flush();
        const bool failed = std::ferror(file_) != 0;
        const int error = errno;
        const bool close_failed = std::fclose(file_) != 0;
        file_ = nullptr;
        if (failed || close_failed) {
            std::remove(path_.c_str());
            throw Error(SH_ERR_IO, format("cannot write '%s': %s", path_.c_str(), std::strerror(error)));
        }
    }

private:
    void append(const char* s, size_t n) {
        if (used_ + n > sizeof buffer_) flush();
        std::memcpy(buffer_ + used_, s, n);
        used_ += n;
    }

    void flush() {
        if (used_ > 0 && std::fwrite(buffer_, 1, used_, file_) != used_)
            throw Error(SH_ERR_IO, format("cannot write '%s': %s", path_.c_str(), std::strerror(errno)));
        used_ = 0;
    }

    std::string path_;
    std::FILE* file_;
    char buffer_[1 << 16];
    size_t used_ = 0;
};

int vtk_cell_type(int nodes_per_cell) {
    switch (nodes_per_cell) {
        case 4: return 10;  // VTK_TETRA
        case 3: return 5;   // VTK_TRIANGLE
        case 2: return 3;   // VTK_LINE
        default: return 0;
    }
}

// One <DataArray> of count rows of `per_row` doubles, a row per line.
void write_reals(VtuOut& out, const char* attributes, const double* values, int64_t count, int per_row) {
    out.text("        <DataArray type=\"Float64\" ");
    out.text(attributes);
    out.text(" format=\"ascii\">\n");
    for (int64_t i = 0; i < count; ++i) {
        out.text("         ");
        for (int k = 0; k < per_row; ++k) {
            out.text(" ");
            out.real(values[i * per_row + k]);
        }
        out.text("\n");
    }
    out.text("        </DataArray>\n");
}

// One <DataArray> of integers, `per_line` per line; value(i) gives the i-th.
template <class Value>
void write_integers(VtuOut& out, const char* attributes, int64_t count, int per_line, Value value) {
    out.text("        <DataArray ");
    out.text(attributes);
    out.text(" format=\"ascii\">\n");
    for (int64_t i = 0; i < count; ++i) {
        out.text(i % per_line == 0 ? "          " : " ");
        out.integer(value(i));
        if (i % per_line == per_line - 1 || i == count - 1) out.text("\n");
    }
    out.text("        </DataArray>\n");
}

}  // namespace

void write_vtu(const std::string& path, const VtuFrame& frame) {
    const int type = vtk_cell_type(frame.nodes_per_cell);
    SH_REQUIRE(type != 0, SH_ERR_INVALID_ARGUMENT, "write_vtu: nodes_per_cell is %d, must be 2, 3 or 4", frame.nodes_per_cell);
    require(frame.point_count >= 0 && frame.cell_count >= 0 && (frame.points || frame.point_count == 0) &&
                (frame.cells || frame.cell_count == 0),
            SH_ERR_INVALID_ARGUMENT, "write_vtu: negative counts or missing arrays");
    const int per_cell = frame.nodes_per_cell;

    VtuOut out(path);
    out.text("<?xml version=\"1.0\"?>\n"
             "<VTKFile type=\"UnstructuredGrid\" version=\"0.1\" byte_order=\"LittleEndian\">\n"
             "  <UnstructuredGrid>\n"
             "    <Piece NumberOfPoints=\"");
    out.integer(frame.point_count);
    out.text("\" NumberOfCells=\"");
    out.integer(frame.cell_count);
    out.text("\">\n");
    if (frame.point_vectors) {
        const std::string name = frame.point_vectors_name ? frame.point_vectors_name : "vectors";
        out.text(("      <PointData Vectors=\"" + name + "\">\n").c_str());
        write_reals(out, ("Name=\"" + name + "\" NumberOfComponents=\"3\"").c_str(), frame.point_vectors,
                    frame.point_count, 3);
        out.text("      </PointData>\n");
    }
    out.text("      <Points>\n");
    write_reals(out, "Name=\"Points\" NumberOfComponents=\"3\"", frame.points, frame.point_count, 3);
    out.text("      </Points>\n      <Cells>\n");
    write_integers(out, "type=\"Int32\" Name=\"connectivity\"", frame.cell_count * per_cell, per_cell,
                   [&](int64_t i) { return static_cast<int64_t>(frame.cells[i]); });
    write_integers(out, "type=\"Int64\" Name=\"offsets\"", frame.cell_count, 16,
                   [&](int64_t i) { return (i + 1) * per_cell; });
    write_integers(out, "type=\"UInt8\" Name=\"types\"", frame.cell_count, 32,
                   [&](int64_t) { return static_cast<int64_t>(type); });
    out.text("      </Cells>\n"
             "    </Piece>\n"
             "  </UnstructuredGrid>\n"
             "</VTKFile>\n");
    out.close();
}

}  // namespace sh
