// TraceWriter: the per-frame trace, JSON Lines (schema in docs/trace.md), written to
// PATH.tmp and renamed to PATH by close(), so a crash never leaves a truncated trace
// under the final name. write() copies into stdio's buffer; no allocation.
#pragma once

#include <cstdio>
#include <string>
#include <string_view>

namespace endotower::app {

class TraceSink {
public:
    virtual ~TraceSink() = default;
    virtual void write(std::string_view json_line) = 0;
};

class TraceWriter final : public TraceSink {
public:
    TraceWriter() = default;
    ~TraceWriter() override;  // an unclosed trace is removed, the old file kept
    TraceWriter(const TraceWriter&) = delete;
    TraceWriter& operator=(const TraceWriter&) = delete;

    // False with error() naming the path when the file cannot be created.
    bool open(const std::string& path);
    void write(std::string_view json_line) override;
    // Flushes, fsyncs and renames into place. False (and the temp removed) on error,
    // e.g. disk full, with error() saying so.
    bool close();
    const std::string& error() const { return error_; }
    long lines() const { return lines_; }

private:
    std::FILE* file_ = nullptr;
    std::string path_, tmp_path_, error_;
    long lines_ = 0;
    bool write_failed_ = false;
    int write_errno_ = 0;
};

}  // namespace endotower::app
