// RecordedFrameSource: frames from a video file (mp4/avi/mkv through OpenCV's FFmpeg
// backend) or a directory of numbered images (png/jpg/bmp/tif, sorted by the number
// in the name), delivered as BGR24.
//
// Pacing: frame i is captured at start + i / fps on the given clock. With a
// MonotonicClock that is real time; with a VirtualClock it is deterministic and as
// fast as decoding allows. The capture timestamp is the scheduled time.
//
// Inputs: path; fps_override (0 = the file's rate, 25 for image directories);
// buffer_count (pool size, default 6). A truncated or corrupt file ends the stream
// at the last good frame (truncated() tells); an unreadable image in a directory is
// skipped and counted (skipped_frames()). Images of another size than the previous
// one give kFormatChange.
#pragma once

#include <cstdint>
#include <memory>
#include <string>

#include "endotower/hal/clock.hpp"
#include "endotower/hal/frame_source.hpp"

namespace endotower::sim {

struct RecordedSourceOptions {
    std::string path;
    double fps_override = 0.0;
    int buffer_count = 6;
    // Video files: play the file this many times in a row (toolchain/soak.sh); the
    // frame index, capture times and sequence numbers run on across the restarts.
    int loops = 1;
};

class RecordedFrameSource final : public hal::FrameSource {
public:
    // Borrows the clock; it must outlive the source.
    RecordedFrameSource(RecordedSourceOptions options, hal::Clock& clock);
    ~RecordedFrameSource() override;

    // Checks the input before start(): exists, readable, decodable, not empty.
    // False with error() naming the path and what is wrong.
    bool open();

    bool start() override;
    void stop() override;
    hal::SourceStatus next(hal::Frame& out, hal::Nanos timeout_ns) override;
    void release(const hal::Frame& frame) override;
    hal::FrameFormat format() const override;
    hal::Nanos frame_period() const override;
    int buffer_count() const override;
    const std::string& error() const override;

    // The exact frame rate behind frame_period(): frame i is captured at
    // start + llround(i * 1e9 / frame_rate()).
    double frame_rate() const;
    // Frames the recording claims to hold (0 if unknown), and what happened so far.
    std::int64_t expected_frames() const;
    std::int64_t frames_read() const;
    std::int64_t skipped_frames() const;
    bool truncated() const;
    // A line for the log when something was skipped or cut short; empty otherwise.
    const std::string& warning() const;

private:
    struct Impl;
    std::unique_ptr<Impl> impl_;
};

}  // namespace endotower::sim
