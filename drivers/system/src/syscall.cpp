#include "endotower/system/syscall.hpp"

#include <fcntl.h>
#include <sys/prctl.h>
#include <unistd.h>

#include <cstring>

namespace endotower::system {

std::string errno_message(std::string_view call, std::string_view what, int err) {
    std::string m(call);
    m += '(';
    m += what;
    m += "): ";
    m += std::strerror(err);
    m += " (errno ";
    m += std::to_string(err);
    m += ')';
    return m;
}

bool write_file_atomic(const std::string& path, std::string_view data, std::string& error) {
    const std::string tmp = path + ".tmp";
    const int fd = retry_eintr([&] { return ::open(tmp.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644); });
    if (fd < 0) {
        error = errno_message("open", tmp, errno);
        return false;
    }
    std::size_t done = 0;
    while (done < data.size()) {
        const ssize_t n = retry_eintr([&] { return ::write(fd, data.data() + done, data.size() - done); });
        if (n < 0) {
            error = errno_message("write", tmp, errno);
            ::close(fd);
            ::unlink(tmp.c_str());
            return false;
        }
        done += static_cast<std::size_t>(n);
    }
    if (retry_eintr([&] { return ::fsync(fd); }) != 0) {
        error = errno_message("fsync", tmp, errno);
        ::close(fd);
        ::unlink(tmp.c_str());
        return false;
    }
    ::close(fd);
    if (::rename(tmp.c_str(), path.c_str()) != 0) {
        error = errno_message("rename", tmp + " -> " + path, errno);
        ::unlink(tmp.c_str());
        return false;
    }
    return true;
}

void tighten_timer_slack() { ::prctl(PR_SET_TIMERSLACK, 1000UL, 0UL, 0UL, 0UL); }

}  // namespace endotower::system
