#include "capi/handles.hpp"

#include "core/error.hpp"
#include "core/memory.hpp"

#include <algorithm>
#include <mutex>

namespace sh::capi {
namespace {

struct Entry {
    HandleKind kind;
    const void* object;
};

std::mutex g_mutex;
vec<Entry>* g_entries = nullptr;  // allocated while any object lives, so it follows the allocator

}  // namespace

void register_handle(HandleKind kind, const void* object) {
    std::lock_guard<std::mutex> lock(g_mutex);
    if (!g_entries) g_entries = sh::create<vec<Entry>>();
    try {
        g_entries->push_back({kind, object});
    } catch (...) {
        if (g_entries->empty()) {
            sh::destroy(g_entries);
            g_entries = nullptr;
        }
        throw;
    }
    object_created();
}

bool unregister_handle(HandleKind kind, const void* object) {
    std::lock_guard<std::mutex> lock(g_mutex);
    if (!g_entries) return false;
    auto it = std::find_if(g_entries->begin(), g_entries->end(), [&](const Entry& e) {
        return e.kind == kind && e.object == object;
    });
    if (it == g_entries->end()) return false;
    *it = g_entries->back();
    g_entries->pop_back();
    object_destroyed();
    if (g_entries->empty()) {
        sh::destroy(g_entries);
        g_entries = nullptr;
    }
    return true;
}

void require_handle(HandleKind kind, const void* object, const char* name) {
    if (!object) throw Error(SH_ERR_INVALID_HANDLE, format("%s is NULL", name));
    std::lock_guard<std::mutex> lock(g_mutex);
    const bool live = g_entries && std::any_of(g_entries->begin(), g_entries->end(), [&](const Entry& e) {
        return e.kind == kind && e.object == object;
    });
    if (!live) throw Error(SH_ERR_INVALID_HANDLE, format("%s is not a live object (destroyed or never created)", name));
}

}  // namespace sh::capi
