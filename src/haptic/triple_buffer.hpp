// TripleIndex: the lock-free hand-over of a triple buffer between one writer thread and one
// reader thread. Three slots of data live elsewhere; this decides which slot each side owns.
// The writer fills its back slot and publishes it; the reader takes the newest published slot
// whenever it likes. Neither ever waits: the only shared state is one atomic byte.
#pragma once

#include <atomic>
#include <cstdint>

namespace sh {

/// Slot ownership of a single-writer, single-reader triple buffer.
class TripleIndex {
public:
    /// The slot the writer fills (Thread: writer).
    int back() const { return back_; }

    /// Hands the back slot over as the newest data and takes the spare slot as the new back
    /// (Thread: writer). Wait-free.
    void publish() { back_ = middle_.exchange(static_cast<uint8_t>(back_ | kFresh), std::memory_order_acq_rel) & kIndex; }

    /// Takes the newest published slot as the front, if one was published since the last take;
    /// returns true if it did (Thread: reader). Wait-free.
    bool take() {
        if (!(middle_.load(std::memory_order_acquire) & kFresh)) return false;
        front_ = middle_.exchange(static_cast<uint8_t>(front_), std::memory_order_acq_rel) & kIndex;
        return true;
    }

    /// The slot the reader reads (Thread: reader).
    int front() const { return front_; }

private:
    static constexpr uint8_t kIndex = 3, kFresh = 4;
    static_assert(std::atomic<uint8_t>::is_always_lock_free, "the exchange must not lock");
    int back_ = 0;   ///< the writer's slot
    int front_ = 1;  ///< the reader's slot
    std::atomic<uint8_t> middle_{2};  ///< the spare slot, with kFresh when it holds unread data
};

}  // namespace sh
