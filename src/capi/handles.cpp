#include "capi/handles.hpp"

#include "core/error.hpp"
#include "core/id_pool.hpp"
#include "core/memory.hpp"

#include <atomic>
#include <mutex>

namespace sh::capi {
namespace {

// A handle is an Id (id_pool.hpp) cast to a pointer: the same encoding and generations as the
// world's ids, so a handle is never NULL and a stale one never names a slot's next object.
static_assert(sizeof(uintptr_t) >= sizeof(Id), "a handle pointer holds a whole id");

// One slot: tag = generation << 8 | kind while live, 0 while free. Published with release
// after the object, read with acquire before it, so a reader that sees the tag sees the object.
struct Slot {
    std::atomic<uint64_t> tag{0};
    std::atomic<void*> object{nullptr};
};

// Static storage, never freed: a stale handle's slot stays readable for the process's life.
Slot g_slots[kMaxLiveHandles];
uint32_t g_next_free[kMaxLiveHandles];   // free list links (under g_mutex)
uint32_t g_free_head = 0;                // the first free slot, or g_used if none
uint32_t g_used = 0;                     // slots ever handed out: [0, g_used)
std::mutex g_mutex;                      // creation and destruction only

uint64_t tag_of(uint32_t generation, HandleKind kind) {
    return static_cast<uint64_t>(generation) << 8 | static_cast<uint64_t>(kind);
}

Id id_of(const void* handle) { return static_cast<Id>(reinterpret_cast<uintptr_t>(handle)); }

}  // namespace

const void* register_handle(HandleKind kind, void* object) {
    std::lock_guard<std::mutex> lock(g_mutex);
    uint32_t index;
    if (g_free_head < g_used) {
        index = g_free_head;
        g_free_head = g_next_free[index];
    } else {
        require(g_used < kMaxLiveHandles, SH_ERR_OUT_OF_MEMORY,
                format("more than %u meshes, worlds and haptic contexts alive at once", kMaxLiveHandles));
        index = g_used++;
        g_free_head = g_used;
    }
    const uint32_t generation = next_generation();
    g_slots[index].object.store(object, std::memory_order_relaxed);
    g_slots[index].tag.store(tag_of(generation, kind), std::memory_order_release);
    object_created();
    return reinterpret_cast<const void*>(static_cast<uintptr_t>(pack_id(index, generation)));
}

void* unregister_handle(HandleKind kind, const void* handle) {
    std::lock_guard<std::mutex> lock(g_mutex);
    void* object = find_handle(kind, handle);
    if (!object) return nullptr;
    const uint32_t index = id_index(id_of(handle));
    g_slots[index].tag.store(0, std::memory_order_release);
    g_slots[index].object.store(nullptr, std::memory_order_relaxed);
    g_next_free[index] = g_free_head;
    g_free_head = index;
    object_destroyed();
    return object;
}

void* find_handle(HandleKind kind, const void* handle) noexcept {
    const Id id = id_of(handle);
    const uint32_t index = id_index(id), generation = id_generation(id);
    if (generation == 0 || index >= kMaxLiveHandles) return nullptr;
    const Slot& slot = g_slots[index];
    if (slot.tag.load(std::memory_order_acquire) != tag_of(generation, kind)) return nullptr;
    return slot.object.load(std::memory_order_relaxed);
}

void* require_handle(HandleKind kind, const void* handle, const char* name) {
    if (!handle) throw Error(SH_ERR_INVALID_HANDLE, format("%s is NULL", name));
    void* object = find_handle(kind, handle);
    if (!object) throw Error(SH_ERR_INVALID_HANDLE, format("%s is not a live object (destroyed or never created)", name));
    return object;
}

}  // namespace sh::capi
