#include "endotower/app/trace_writer.hpp"

#include <unistd.h>

#include <cerrno>
#include <cstring>

namespace endotower::app {

namespace {
std::string describe(const char* call, const std::string& path, int err) {
    return std::string(call) + "(" + path + "): " + std::strerror(err);
}
}  // namespace

TraceWriter::~TraceWriter() {
    if (file_ != nullptr) {
        std::fclose(file_);
        std::remove(tmp_path_.c_str());
    }
}

bool TraceWriter::open(const std::string& path) {
    path_ = path;
    tmp_path_ = path + ".tmp";
    file_ = std::fopen(tmp_path_.c_str(), "w");
    if (file_ == nullptr) {
        error_ = "cannot write trace: " + describe("fopen", tmp_path_, errno);
        return false;
    }
    // A large stdio buffer: one write(2) per ~64 lines instead of per frame.
    std::setvbuf(file_, nullptr, _IOFBF, 1 << 20);
    return true;
}

void TraceWriter::write(std::string_view json_line) {
    if (file_ == nullptr || write_failed_) return;
    if (std::fwrite(json_line.data(), 1, json_line.size(), file_) != json_line.size() ||
        std::fputc('\n', file_) == EOF) {
        // Disk full or I/O error: stop tracing, never stop the video. close() reports.
        write_failed_ = true;
        write_errno_ = errno;
        return;
    }
    ++lines_;
}

bool TraceWriter::close() {
    if (file_ == nullptr) return error_.empty();
    bool ok = !write_failed_;
    if (!ok) error_ = "trace not saved: " + describe("write", tmp_path_, write_errno_);
    if (ok && std::fflush(file_) != 0) {
        ok = false;
        error_ = "trace not saved: " + describe("fflush", tmp_path_, errno);
    }
    if (ok && ::fsync(fileno(file_)) != 0) {
        ok = false;
        error_ = "trace not saved: " + describe("fsync", tmp_path_, errno);
    }
    std::fclose(file_);
    file_ = nullptr;
    if (ok && std::rename(tmp_path_.c_str(), path_.c_str()) != 0) {
        ok = false;
        error_ = "trace not saved: " + describe("rename", tmp_path_, errno);
    }
    if (!ok) std::remove(tmp_path_.c_str());
    return ok;
}

}  // namespace endotower::app
