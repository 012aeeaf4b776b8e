// What every mesh-reader fuzz target checks. The targets go through the public C API as a host
// does (tests include no header of src/: scripts/check_layers.py): each input is written to a
// file in a private temporary folder and loaded with sh_mesh_load, which runs the extension
// dispatch, the reader and mesh validation behind the C guard. The load must either succeed,
// giving a mesh whose tets index its nodes, or fail with a file-content status (SH_ERR_PARSE,
// SH_ERR_UNSUPPORTED, SH_ERR_DEGENERATE_MESH) whose message names the file, and for a parse or
// format error a line that the file has. Any other status (SH_ERR_INTERNAL: something other than
// an sh::Error escaped a reader; SH_ERR_IO, SH_ERR_OUT_OF_MEMORY) aborts, and libFuzzer keeps the
// input, as it does for a crash, a leak, undefined behaviour or a hang.
#pragma once

#include <softhap/softhap.h>

#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <initializer_list>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

#include <unistd.h>

namespace softhap_fuzz {

/// One file of an input, as written: its path and content.
struct File {
    std::string path;
    std::string_view text;
};

/// Destroys a loaded mesh.
struct MeshDeleter {
    void operator()(sh_mesh* mesh) const { sh_mesh_destroy(mesh); }
};
using MeshPtr = std::unique_ptr<sh_mesh, MeshDeleter>;

/// The input bytes as text (the readers take any bytes, NULs included).
inline std::string_view as_text(const uint8_t* data, size_t size) {
    return std::string_view(reinterpret_cast<const char*>(data), size);
}

/// Prints what was violated and aborts: libFuzzer keeps the input as a crash.
[[noreturn]] inline void violated(const char* what, const std::string& detail) {
    std::fprintf(stderr, "fuzz check failed: %s: %s\n", what, detail.c_str());
    std::abort();
}

/// The private folder inputs are written to, made on first use: in /dev/shm where it can be
/// (memory, not disk: the fuzzers write thousands of files a second), else in $TMPDIR or /tmp.
/// Removed with its files at exit (not after a crash: libFuzzer aborts then).
class TempDir {
public:
    TempDir() {
        const char* tmp = std::getenv("TMPDIR");
        for (const char* base : {"/dev/shm", tmp, "/tmp"}) {
            if (!base) continue;
            path_ = std::string(base) + "/softhap_fuzz_XXXXXX";
            if (mkdtemp(path_.data())) return;
        }
        violated("cannot make a temporary folder", "in /dev/shm, $TMPDIR or /tmp");
    }

    ~TempDir() {
        for (const std::string& path : written_) std::remove(path.c_str());
        rmdir(path_.c_str());
    }

    /// Writes text to the file name in this folder (replacing it).
    File write(const char* name, std::string_view text) {
        File file{path_ + "/" + name, text};
        std::FILE* out = std::fopen(file.path.c_str(), "wb");
        if (!out || std::fwrite(text.data(), 1, text.size(), out) != text.size() || std::fclose(out) != 0)
            violated("cannot write", file.path);
        bool known = false;
        for (const std::string& path : written_) known = known || path == file.path;
        if (!known) written_.push_back(file.path);
        return file;
    }

private:
    std::string path_;
    std::vector<std::string> written_;  // a few fixed names
};

/// Writes text to name in the fuzzer's temporary folder; the File views text, which must outlive it.
inline File write_input(const char* name, std::string_view text) {
    static TempDir dir;
    return dir.write(name, text);
}

/// Number of lines of text (a last line without '\n' counts; an empty text has one).
inline long line_count(std::string_view text) {
    long lines = 1;
    for (size_t i = 0; i + 1 < text.size(); ++i) lines += text[i] == '\n' ? 1 : 0;
    return lines;
}

/// True if message starts with "<file.path>:<line>: " for a line in [1, lines of the file].
inline bool names_file_line(std::string_view message, const File& file) {
    if (message.substr(0, file.path.size() + 1) != file.path + ":") return false;
    size_t i = file.path.size() + 1;
    long line = 0;
    while (i < message.size() && message[i] >= '0' && message[i] <= '9' && line <= 1000000000)
        line = 10 * line + (message[i++] - '0');
    return i > file.path.size() + 1 && message.substr(i, 2) == ": " && line >= 1 && line <= line_count(file.text);
}

/// Checks a refused load: a file-content status, and a message naming the file it is about
/// (validation names the loaded path; a parse or format error, a line of one of files).
inline void check_refusal(sh_status status, const std::string& loaded, std::initializer_list<File> files) {
    const std::string message = sh_last_error_message();
    const std::string detail = std::string(sh_status_string(status)) + ": " + message;
    if (status == SH_ERR_DEGENERATE_MESH) {
        if (message.compare(0, loaded.size() + 2, loaded + ": ") != 0)
            violated("a degenerate-mesh message does not start with the file's path", detail);
        return;
    }
    if (status != SH_ERR_PARSE && status != SH_ERR_UNSUPPORTED)
        violated("a load failed with a status other than parse, unsupported or degenerate mesh", detail);
    for (const File& file : files)
        if (names_file_line(message, file)) return;
    violated("a parse or format error does not name the file and a line of it", detail);
}

/// Checks a loaded mesh: some tets, every tet index a node.
inline void check_mesh(const sh_mesh* mesh) {
    sh_mesh_info info;
    if (sh_mesh_get_info(mesh, &info) != SH_OK || info.tet_count <= 0)
        violated("a loaded mesh has no tets", sh_last_error_message());
    std::vector<int32_t> tets(4 * static_cast<size_t>(info.tet_count));
    if (sh_mesh_get_tets(mesh, tets.data(), static_cast<int32_t>(tets.size() / 4)) != SH_OK)
        violated("cannot read a loaded mesh's tets", sh_last_error_message());
    for (const int32_t index : tets)
        if (index < 0 || index >= info.node_count) violated("a loaded tet indexes no node", std::to_string(index));
}

/// Loads loaded (one of files, the files of the input) with sh_mesh_load and checks the outcome;
/// returns the mesh, or null if it was refused.
inline MeshPtr check_load(const std::string& loaded, std::initializer_list<File> files) {
    sh_mesh* mesh = nullptr;
    const sh_status status = sh_mesh_load(loaded.c_str(), &mesh);
    if (status != SH_OK) {
        check_refusal(status, loaded, files);
        return nullptr;
    }
    check_mesh(mesh);
    return MeshPtr(mesh);
}

/// The whole check for a one-file format: the input written as name, then loaded.
inline void check_file(const char* name, const uint8_t* data, size_t size) {
    const File file = write_input(name, as_text(data, size));
    check_load(file.path, {file});
}

}  // namespace softhap_fuzz
