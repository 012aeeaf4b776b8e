// Elapsed-time measurement for the cost figures of step and solve reports.
#pragma once

#include <chrono>

namespace sh {

/// Seconds on a monotonic clock; only differences mean anything.
inline double now_seconds() {
    return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

/// Adds the seconds of its lifetime to total.
class ScopedTimer {
public:
    explicit ScopedTimer(double& total) : total_(total), start_(now_seconds()) {}
    ~ScopedTimer() { total_ += now_seconds() - start_; }
    ScopedTimer(const ScopedTimer&) = delete;
    ScopedTimer& operator=(const ScopedTimer&) = delete;

private:
    double& total_;
    double start_;
};

}  // namespace sh
