// Every softhap allocation goes through the host-installable allocator (sh_set_allocator).
#pragma once

#include <softhap/softhap.h>

#include <cstddef>
#include <new>
#include <utility>
#include <vector>

namespace sh {

/// Allocates size bytes aligned to alignment through the installed allocator; throws
/// std::bad_alloc on failure.
void* allocate(size_t size, size_t alignment);

/// Releases memory from allocate (nullptr is fine).
void deallocate(void* ptr);

/// Number of live softhap objects (worlds, meshes); sh_set_allocator needs zero.
int live_object_count();

/// Called by object constructors and destructors to keep live_object_count.
void object_created();
void object_destroyed();

/// std allocator adaptor over sh::allocate, 64-byte aligned (cache line, AVX-512).
template <class T>
struct Allocator {
    using value_type = T;
    Allocator() noexcept = default;
    template <class U>
    Allocator(const Allocator<U>&) noexcept {}
    T* allocate(size_t n) {
        if (n > static_cast<size_t>(-1) / sizeof(T)) throw std::bad_alloc();
        return static_cast<T*>(sh::allocate(n * sizeof(T), 64));
    }
    void deallocate(T* p, size_t) noexcept { sh::deallocate(p); }
    template <class U>
    bool operator==(const Allocator<U>&) const noexcept { return true; }
    template <class U>
    bool operator!=(const Allocator<U>&) const noexcept { return false; }
};

/// The container every softhap array uses.
template <class T>
using vec = std::vector<T, Allocator<T>>;

/// Makes room in v for n elements without changing its contents; grows the capacity by at
/// least half when it must grow, so that a body that gains a few nodes or elements at a time
/// (cut after cut) copies its arrays amortised O(1) times per element. Throws std::bad_alloc.
template <class T>
void reserve_growing(vec<T>& v, size_t n) {
    if (v.capacity() < n) v.reserve(n > v.capacity() + v.capacity() / 2 ? n : v.capacity() + v.capacity() / 2);
}

/// Constructs a T in memory from sh::allocate.
template <class T, class... Args>
T* create(Args&&... args) {
    void* mem = allocate(sizeof(T), alignof(T) > 16 ? alignof(T) : 16);
    try {
        return new (mem) T(std::forward<Args>(args)...);
    } catch (...) {
        deallocate(mem);
        throw;
    }
}

/// Destroys and frees an object made by create (nullptr is fine).
template <class T>
void destroy(T* object) {
    if (!object) return;
    object->~T();
    deallocate(object);
}

}  // namespace sh

namespace sh {
/// Installs allocator (nullptr: the default aligned malloc/free). Callers check liveness.
void set_allocator(const sh_allocator* allocator);
}  // namespace sh
