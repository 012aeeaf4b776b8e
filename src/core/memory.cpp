#include "core/memory.hpp"

#include <softhap/softhap.h>

#include <atomic>
#include <cstdlib>

namespace sh {
namespace {

void* default_alloc(size_t size, size_t alignment, void*) {
    const size_t rounded = (size + alignment - 1) / alignment * alignment;
    return std::aligned_alloc(alignment, rounded == 0 ? alignment : rounded);
}

void default_free(void* ptr, void*) { std::free(ptr); }

sh_allocator g_allocator = {default_alloc, default_free, nullptr};
std::atomic<int> g_live_objects{0};

}  // namespace

void* allocate(size_t size, size_t alignment) {
    void* p = g_allocator.alloc(size, alignment, g_allocator.user);
    if (!p) throw std::bad_alloc();
    return p;
}

void deallocate(void* ptr) {
    if (ptr) g_allocator.free(ptr, g_allocator.user);
}

int live_object_count() { return g_live_objects.load(); }
void object_created() { g_live_objects.fetch_add(1); }
void object_destroyed() { g_live_objects.fetch_sub(1); }

void set_allocator(const sh_allocator* allocator) {
    g_allocator = allocator ? *allocator : sh_allocator{default_alloc, default_free, nullptr};
}

}  // namespace sh
