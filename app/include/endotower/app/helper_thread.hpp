// HelperThread: one thread that runs a job beside its owner, for the per-frame loops
// that split an image's rows in two (the board has two cores; the calling thread takes
// one half, the helper the other: the undistortion remap and the gesture segmenter's
// reduction wait on memory, and two cores fetch it faster than one).
//
// post(job, arg) hands the helper `job(arg)`; wait() returns once it has run. One job at
// a time, posted and waited for by the owner's thread; the job must not throw. The
// thread starts in the constructor and is joined in the destructor. No allocation and
// no system call beyond the futex wake-ups per job. The constructor throws
// std::system_error when no thread can be started (a process limit); the users catch
// it and stay on one thread.
#pragma once

#include <condition_variable>
#include <cstdint>
#include <mutex>
#include <thread>

namespace endotower::app {

class HelperThread {
public:
    using Job = void (*)(void*);
    HelperThread();
    ~HelperThread();
    HelperThread(const HelperThread&) = delete;
    HelperThread& operator=(const HelperThread&) = delete;

    void post(Job job, void* arg);
    void wait();

private:
    void loop();

    std::mutex mutex_;
    std::condition_variable cv_;
    Job job_ = nullptr;
    void* arg_ = nullptr;
    std::uint64_t posted_ = 0, done_ = 0;
    bool quit_ = false;
    std::thread thread_;  // last: starts once the members above exist
};

}  // namespace endotower::app
