// Log: where the pipeline reports faults and state changes (never once per frame in
// steady state). Messages are formatted into a stack buffer: no allocation.
#pragma once

#include <string_view>

namespace endotower::app {

enum class LogLevel { kInfo, kWarning, kError };

class Log {
public:
    virtual ~Log() = default;
    virtual void write(LogLevel level, std::string_view message) = 0;

    // printf-style convenience; truncates past 512 bytes.
    void printf(LogLevel level, const char* fmt, ...) __attribute__((format(printf, 3, 4)));
};

// Writes "endotower: warning: ..." lines to stderr.
class StderrLog final : public Log {
public:
    void write(LogLevel level, std::string_view message) override;
};

}  // namespace endotower::app
