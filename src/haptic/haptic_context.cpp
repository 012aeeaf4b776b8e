#include "haptic/haptic_context.hpp"

#include "contact/shape_contact.hpp"

#include "core/error.hpp"
#include "model/fem_body.hpp"
#include "world/world.hpp"

#include <cmath>
#include <cstring>

namespace sh {
namespace {

// The haptic side's working arrays, carved after the three buffers.
struct WorkingArrays {
    double* x[2];
    double* v[2];
    int32_t* id[2];
    double* force;
    double* contact;
    double* contact_tangent;
    int32_t* contacted;
    uint8_t* in_contact;
    double* saved_x;
    double* saved_v;
    double* path_x;
    double* path_v;
    double* held_pull;
    FrictionRecord* friction;
    Mat3L* rotations;
};

void carve_all(Arena& arena, const BufferCapacity& capacity, Buffer (&buffers)[3], WorkingArrays& w) {
    for (Buffer& b : buffers) b.carve(arena, capacity);
    const size_t n = static_cast<size_t>(capacity.nodes);
    for (int k = 0; k < 2; ++k) {
        w.x[k] = arena.take<double>(3 * n);
        w.v[k] = arena.take<double>(3 * n);
        w.id[k] = arena.take<int32_t>(n);
    }
    w.force = arena.take<double>(3 * n);
    w.contact = arena.take<double>(3 * n);
    w.contact_tangent = arena.take<double>(HapticContext::kTangentStride * n);
    w.contacted = arena.take<int32_t>(n);
    w.in_contact = arena.take<uint8_t>(n);
    w.saved_x = arena.take<double>(3 * n);
    w.saved_v = arena.take<double>(3 * n);
    w.path_x = arena.take<double>(3 * n);
    w.path_v = arena.take<double>(3 * n);
    w.held_pull = arena.take<double>(3 * n);
    w.friction = arena.take<FrictionRecord>(static_cast<size_t>(capacity.friction_records()));
    w.rotations = arena.take<Mat3L>(static_cast<size_t>(capacity.blocks()));
}

BufferCapacity capacity_of(const sh_haptic_def& def) { return BufferCapacity{def.capacity_tets, def.capacity_nodes}; }

ForceLimits limits_of(const sh_haptic_def& def) {
    return ForceLimits{def.max_force, def.max_force_rate, def.ramp_time};
}

void require_range(double value, double lo, double hi, bool lo_open, const char* name) {
    const bool ok = std::isfinite(value) && (lo_open ? value > lo : value >= lo) && value <= hi;
    SH_REQUIRE(ok, SH_ERR_INVALID_ARGUMENT, "def->%s = %g must be finite and in %s%g, %g]", name, value,
               lo_open ? "(" : "[", lo, hi);
}

}  // namespace

void validate_haptic_def(const sh_haptic_def& def) {
    SH_REQUIRE(def.capacity_tets >= 1 && def.capacity_tets <= 10000000, SH_ERR_INVALID_ARGUMENT,
               "def->capacity_tets = %d must be in [1, 1e7]", def.capacity_tets);
    SH_REQUIRE(def.capacity_nodes >= 4 && def.capacity_nodes <= 10000000, SH_ERR_INVALID_ARGUMENT,
               "def->capacity_nodes = %d must be in [4, 1e7]", def.capacity_nodes);
    SH_REQUIRE(def.rings >= 0 && def.rings <= 1000, SH_ERR_INVALID_ARGUMENT, "def->rings = %d must be in [0, 1000]",
               def.rings);
    require_range(def.radius, 0.0, 1e3, true, "radius");
    require_range(def.dt, 0.0, 1.0, true, "dt");
    require_range(def.max_force, 0.0, 1e6, true, "max_force");
    require_range(def.max_force_rate, 0.0, 1e12, true, "max_force_rate");
    require_range(def.ramp_time, 0.0, 1e3, false, "ramp_time");
    require_range(def.stale_after, 0.0, 1e3, true, "stale_after");
    SH_REQUIRE(def.stale_after >= def.dt, SH_ERR_INVALID_ARGUMENT,
               "def->stale_after = %g s is shorter than def->dt = %g s: every step would be stale", def.stale_after,
               def.dt);
}

size_t HapticContext::memory_bytes(const sh_haptic_def& def) {
    Arena measure;
    Buffer buffers[3];
    WorkingArrays w{};
    carve_all(measure, capacity_of(def), buffers, w);
    return measure.used();
}

HapticContext::HapticContext(World& world, const sh_haptic_def& def)
    : def_(def), world_(&world), tool_(world.collider(def.tool.value, true)), filter_(limits_of(def)) {
    validate_haptic_def(def);
    tool_.shape.use_allocation_free_queries();
    balls_.reserve(tool_.shape.ball_count());
    arena_bytes_ = memory_bytes(def);
    arena_ = allocate(arena_bytes_, 64);
    Arena arena(arena_, arena_bytes_);
    WorkingArrays w{};
    carve_all(arena, capacity_of(def), buffers_, w);
    for (int k = 0; k < 2; ++k) {
        x_[k] = w.x[k];
        v_[k] = w.v[k];
        id_[k] = w.id[k];
    }
    force_ = w.force;
    contact_ = w.contact;
    contact_tangent_ = w.contact_tangent;
    contacted_ = w.contacted;
    in_contact_ = w.in_contact;
    saved_x_ = w.saved_x;
    saved_v_ = w.saved_v;
    path_x_ = w.path_x;
    path_v_ = w.path_v;
    held_pull_ = w.held_pull;
    friction_ = w.friction;
    rotation_ = w.rotations;
    friction_capacity_ = capacity_of(def).friction_records();
    pose_ = tool_.target;
    try {
        extract(world, 0.0, buffers_[buffer_index_.back()]);
        buffer_index_.publish();
    } catch (...) {
        deallocate(arena_);
        throw;
    }
}

HapticContext::~HapticContext() { deallocate(arena_); }

void HapticContext::detach() {
    world_ = nullptr;
    detached_.store(true, std::memory_order_release);
}

void HapticContext::before_step(World& world) {
    if (device_index_.take()) {
        const DevicePose& d = device_[device_index_.front()];
        if (d.valid && world.is_valid_collider(def_.tool.value, true)) {
            Collider& tool = world.collider(def_.tool.value, true);
            tool.target = d.pose;
        }
    }
    // The buffer's boundary moves across the step from where the step starts.
    x_before_body_ = 0;
    world.for_each_body([&](Id id, const Body& body) {
        if (id != extracted_body_) return;
        x_before_.assign(body.x.begin(), body.x.end());
        x_before_body_ = id;
    });
}

void HapticContext::after_step(World& world, double dt) {
    extract(world, dt, buffers_[buffer_index_.back()]);
    buffer_index_.publish();
}

void HapticContext::topology_changed(World& world, Id id) noexcept {
    if (id != extracted_body_) return;
    x_before_body_ = 0;
    try {
        extract(world, 0.0, buffers_[buffer_index_.back()]);
        buffer_index_.publish();
    } catch (...) {
        // Out of memory on the sim side: the device keeps the last buffer until the next step.
    }
}

void HapticContext::read_warnings(uint64_t out[SH_WARN_COUNT]) const {
    for (int k = 0; k < SH_WARN_COUNT; ++k) out[k] = warnings_[k].load(std::memory_order_relaxed);
}

}  // namespace sh
