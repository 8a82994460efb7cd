// System-call helpers: retry on EINTR, and errors that carry the call and errno.
#pragma once

#include <cerrno>
#include <string>
#include <string_view>

namespace endotower::system {

// Calls fn() again while it fails with EINTR; returns its last result.
template <typename Fn>
auto retry_eintr(Fn&& fn) {
    for (;;) {
        auto r = fn();
        if (!(r == -1 && errno == EINTR)) return r;
    }
}

// "CALL(WHAT): strerror (errno N)", e.g. "open(/dev/video0): No such file (errno 2)".
std::string errno_message(std::string_view call, std::string_view what, int err);

// Writes `data` to `path` atomically: a temporary file in the same directory,
// fsync, then rename over the old one. On failure the old file is untouched and
// `error` says what failed.
bool write_file_atomic(const std::string& path, std::string_view data, std::string& error);

// Sets the calling thread's timer slack to 1 us (prctl PR_SET_TIMERSLACK), so that
// absolute sleeps of the video thread wake within microseconds of their deadline.
void tighten_timer_slack();

}  // namespace endotower::system
