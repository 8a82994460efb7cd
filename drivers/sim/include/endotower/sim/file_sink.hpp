// FileSink: the simulation's monitor. Composes video + overlay on the CPU and writes
// a video file and/or numbered PNG frames (DIR/000000.png, ...).
//
// Video container by extension: .mkv -> FFV1 (lossless), .avi -> MJPG, .mp4 -> mp4v.
// Everything is written under a temporary name and renamed by finish(), so a crash
// never leaves a half-written file under the final name. A format change starts a
// new segment: out.mkv, then out.1.mkv, out.2.mkv, ...
//
// present() waits on the clock until the due time (a virtual clock jumps), and
// returns max(due, now) as the presentation time.
#pragma once

#include <memory>
#include <string>

#include "endotower/hal/clock.hpp"
#include "endotower/hal/video_sink.hpp"

namespace endotower::sim {

struct FileSinkOptions {
    std::string video_path;  // empty: no video file
    std::string frames_dir;  // empty: no PNG frames; created if missing
    double fps = 25.0;       // the video file's nominal rate
};

class FileSink final : public hal::VideoSink {
public:
    FileSink(FileSinkOptions options, hal::Clock& clock);
    ~FileSink() override;

    bool configure(const hal::FrameFormat& format) override;
    hal::Nanos present(const hal::Frame& video, const hal::OverlayLayer* overlay,
                       hal::Nanos due_ns) override;
    bool finish() override;
    const std::string& error() const override;

    std::int64_t frames_written() const;

private:
    struct Impl;
    std::unique_ptr<Impl> impl_;
};

}  // namespace endotower::sim
