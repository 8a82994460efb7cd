// HelperThread (helper_thread.hpp).
#include "endotower/app/helper_thread.hpp"

namespace endotower::app {

HelperThread::HelperThread() : thread_([this] { loop(); }) {}

HelperThread::~HelperThread() {
    {
        std::lock_guard lock(mutex_);
        quit_ = true;
    }
    cv_.notify_all();
    thread_.join();
}

void HelperThread::post(Job job, void* arg) {
    {
        std::lock_guard lock(mutex_);
        job_ = job;
        arg_ = arg;
        ++posted_;
    }
    cv_.notify_all();
}

void HelperThread::wait() {
    std::unique_lock lock(mutex_);
    cv_.wait(lock, [this] { return done_ == posted_; });
}

void HelperThread::loop() {
    std::uint64_t seen = 0;
    std::unique_lock lock(mutex_);
    for (;;) {
        cv_.wait(lock, [&] { return quit_ || posted_ != seen; });
        if (quit_) return;
        seen = posted_;
        const Job job = job_;
        void* arg = arg_;
        lock.unlock();
        job(arg);
        lock.lock();
        done_ = seen;
        cv_.notify_all();
    }
}

}  // namespace endotower::app
