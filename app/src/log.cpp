#include "endotower/app/log.hpp"

#include <algorithm>
#include <cstdarg>
#include <cstdio>

namespace endotower::app {

void Log::printf(LogLevel level, const char* fmt, ...) {
    char buf[512];
    va_list ap;
    va_start(ap, fmt);
    const int n = std::vsnprintf(buf, sizeof buf, fmt, ap);
    va_end(ap);
    if (n < 0) return;
    write(level, std::string_view(buf, std::min<std::size_t>(static_cast<std::size_t>(n), sizeof buf - 1)));
}

void StderrLog::write(LogLevel level, std::string_view message) {
    const char* tag = level == LogLevel::kError ? "error: " : level == LogLevel::kWarning ? "warning: " : "";
    std::fprintf(stderr, "endotower: %s%.*s\n", tag, static_cast<int>(message.size()), message.data());
}

}  // namespace endotower::app
