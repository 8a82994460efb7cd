// FramePool: the fixed set of frame buffers a source lends out (private to the sim
// backend). allocate() and acquire() belong to the capture thread; release() may
// come from any thread.
#pragma once

#include <chrono>
#include <condition_variable>
#include <cstddef>
#include <cstdint>
#include <mutex>
#include <new>
#include <vector>

#include "endotower/hal/time.hpp"

namespace endotower::sim {

class FramePool {
public:
    // All buffers, `bytes` each. Must not be called while buffers are lent.
    bool allocate(int count, std::size_t bytes) {
        try {
            buffers_.assign(static_cast<std::size_t>(count), std::vector<std::uint8_t>(bytes));
        } catch (const std::bad_alloc&) {
            buffers_.clear();
            return false;
        }
        std::lock_guard lock(mu_);
        lent_.assign(static_cast<std::size_t>(count), 0);
        return true;
    }

    // A free buffer of at least `bytes`, waiting (in real time) up to timeout_ns for
    // a release(); -1 if none. Only a format change to a larger size grows a buffer.
    int acquire(std::size_t bytes, hal::Nanos timeout_ns) {
        std::unique_lock lock(mu_);
        int slot = find_free();
        if (slot < 0 && timeout_ns > 0) {
            freed_.wait_for(lock, std::chrono::nanoseconds(timeout_ns),
                            [&] { return (slot = find_free()) >= 0; });
        }
        if (slot < 0) return -1;
        lent_[static_cast<std::size_t>(slot)] = 1;
        lock.unlock();
        // The buffer's bytes belong to this thread until it is released, so growing it
        // needs no lock.
        std::vector<std::uint8_t>& buf = buffers_[static_cast<std::size_t>(slot)];
        if (buf.size() < bytes) buf.resize(bytes);
        return slot;
    }

    // Gives a lent buffer back; an index that is not lent (a double release) is ignored.
    void release(int slot) {
        {
            std::lock_guard lock(mu_);
            if (slot < 0 || static_cast<std::size_t>(slot) >= lent_.size() ||
                !lent_[static_cast<std::size_t>(slot)])
                return;
            lent_[static_cast<std::size_t>(slot)] = 0;
        }
        freed_.notify_one();
    }

    std::uint8_t* data(int slot) { return buffers_[static_cast<std::size_t>(slot)].data(); }

private:
    int find_free() const {
        for (std::size_t i = 0; i < lent_.size(); ++i)
            if (!lent_[i]) return static_cast<int>(i);
        return -1;
    }

    std::vector<std::vector<std::uint8_t>> buffers_;  // sized by allocate() only
    std::mutex mu_;
    std::condition_variable freed_;
    std::vector<char> lent_;  // guarded by mu_
};

}  // namespace endotower::sim
