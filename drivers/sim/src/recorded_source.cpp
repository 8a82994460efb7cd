#include "endotower/sim/recorded_source.hpp"

#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/videoio.hpp>
#include <vector>

#include "endotower/system/syscall.hpp"
#include "frame_pool.hpp"
#include "image_sequence.hpp"

namespace endotower::sim {

namespace {

namespace fs = std::filesystem;
using detail::to_bgr24;
using hal::FrameFormat;
using hal::Nanos;
using hal::PixelFormat;
using hal::SourceStatus;

constexpr double kDefaultFps = 25.0;
constexpr double kMaxFps = 1000.0;  // above this a container's rate is nonsense

double sane_fps(double fps) {
    return !std::isfinite(fps) || fps <= 0.0 || fps > kMaxFps ? kDefaultFps : fps;
}

Nanos period_from_fps(double fps) { return static_cast<Nanos>(std::llround(1e9 / sane_fps(fps))); }

FrameFormat bgr24_format(int width, int height) {
    return FrameFormat{width, height, width * 3, PixelFormat::kBgr24};
}

}  // namespace

struct RecordedFrameSource::Impl {
    RecordedSourceOptions opt;
    hal::Clock& clock;
    std::string error;
    std::string warning;

    bool is_dir = false;
    bool opened = false;
    bool started = false;
    bool ended = false;
    std::vector<std::string> files;  // image directory, in frame order
    std::size_t next_file = 0;
    std::string first_skipped;
    cv::VideoCapture cap;
    std::int64_t next_video_index = 0;

    FrameFormat format{};
    Nanos period = period_from_fps(kDefaultFps);
    double fps = kDefaultFps;  // capture times come from it, so they do not drift
    Nanos t0 = 0;
    int loops_done = 0;
    std::int64_t expected = 0;
    std::int64_t read = 0;
    std::int64_t skipped = 0;
    bool truncated = false;

    // A frame decoded outside the pool (the first one, probed by open(), or the one
    // after a format change), waiting for a free buffer.
    cv::Mat staged;
    cv::Mat scratch;  // reused by conversions and image decoding
    bool has_staged = false;
    std::int64_t staged_index = 0;
    // A buffer already filled but not yet handed out (its due time is still ahead).
    int ready_slot = -1;
    std::int64_t ready_index = 0;

    FramePool pool;

    Impl(RecordedSourceOptions o, hal::Clock& c) : opt(std::move(o)), clock(c) {}

    bool fail(std::string msg) {
        error = std::move(msg);
        return false;
    }

    void reset_state() {
        cap.release();
        files.clear();
        opened = started = ended = truncated = has_staged = false;
        next_file = 0;
        next_video_index = 0;
        expected = read = skipped = 0;
        ready_slot = -1;
        warning.clear();
        first_skipped.clear();
        error.clear();
    }

    // Decodes one image; false (and the image counts as skipped) if unreadable.
    bool decode_image(const std::string& path) {
        try {
            cv::Mat img = cv::imread(path, cv::IMREAD_COLOR);
            const cv::Mat* bgr = nullptr;
            if (!to_bgr24(img, scratch, bgr)) return note_skipped(path);
            if (bgr == &img)
                staged = std::move(img);
            else
                cv::swap(staged, scratch);
            return true;
        } catch (const cv::Exception&) {
            return note_skipped(path);
        }
    }

    bool note_skipped(const std::string& path) {
        if (skipped++ == 0) first_skipped = path;
        warning = "skipped " + std::to_string(skipped) + " unreadable image(s) in " + opt.path +
                  " (first: " + first_skipped + ")";
        return false;
    }

    bool open_directory() {
        std::error_code ec;
        files = detail::list_image_sequence(opt.path, ec);
        if (ec) return fail("cannot list recording directory: " + opt.path + ": " + ec.message());
        if (files.empty()) return fail("no images (png/jpg/bmp/tif) in directory: " + opt.path);
        expected = static_cast<std::int64_t>(files.size());
        fps = sane_fps(opt.fps_override > 0.0 ? opt.fps_override : kDefaultFps);
        period = period_from_fps(fps);

        // The first readable image gives the format; unreadable ones before it are skipped.
        while (next_file < files.size()) {
            const std::size_t i = next_file++;
            if (decode_image(files[i])) {
                has_staged = true;
                staged_index = static_cast<std::int64_t>(i);
                format = bgr24_format(staged.cols, staged.rows);
                return true;
            }
        }
        return fail("no readable image in directory: " + opt.path + " (" +
                    std::to_string(files.size()) + " files, none could be decoded)");
    }

    bool open_video() {
        if (::access(opt.path.c_str(), R_OK) != 0) {
            const int err = errno;  // before anything else can change it
            return fail("recording not readable: " +
                        system::errno_message("access", opt.path, err));
        }
        try {
            if (!cap.open(opt.path, cv::CAP_FFMPEG) || !cap.isOpened())
                return fail("cannot decode video: " + opt.path +
                            " (unsupported codec or not a video)");
            const double count = cap.get(cv::CAP_PROP_FRAME_COUNT);
            expected = std::isfinite(count) && count > 0 ? static_cast<std::int64_t>(count) : 0;
            fps = sane_fps(opt.fps_override > 0.0 ? opt.fps_override : cap.get(cv::CAP_PROP_FPS));
            period = period_from_fps(fps);
            cv::Mat first;
            const cv::Mat* bgr = nullptr;
            if (!cap.read(first) || !to_bgr24(first, scratch, bgr))
                return fail("cannot read the first frame of video: " + opt.path +
                            " (empty, truncated or corrupt)");
            bgr->copyTo(staged);
        } catch (const cv::Exception& e) {
            return fail("cannot decode video: " + opt.path + " (" + e.what() + ")");
        }
        has_staged = true;
        staged_index = 0;
        next_video_index = 1;
        format = bgr24_format(staged.cols, staged.rows);
        return true;
    }

    bool open() {
        reset_state();
        std::error_code ec;
        const fs::file_status st = fs::status(opt.path, ec);
        if (opt.path.empty() || !fs::exists(st)) return fail("recording not found: " + opt.path);
        is_dir = fs::is_directory(st);
        if (!(is_dir ? open_directory() : open_video())) {
            cap.release();
            return false;
        }
        opened = true;
        return true;
    }

    int acquire(Nanos timeout_ns) { return pool.acquire(format.size_bytes(), timeout_ns); }

    void copy_staged(int slot) {
        const cv::Mat& m = staged;
        std::uint8_t* dst = pool.data(slot);
        const std::size_t row = static_cast<std::size_t>(format.width) * 3;
        for (int y = 0; y < format.height; ++y)
            std::memcpy(dst + static_cast<std::size_t>(y) * format.stride, m.ptr(y), row);
    }

    void end_video() {
        ended = true;
        if (!is_dir && expected > 0 && read < expected) {
            truncated = true;
            warning = "recording " + opt.path + " ends after " + std::to_string(read) + " of " +
                      std::to_string(expected) + " frames (truncated or corrupt)";
        }
    }

    // Fills a pool buffer with the next frame (ready_slot), or says why not.
    SourceStatus fill(Nanos timeout_ns) {
        if (has_staged) {
            const int slot = acquire(timeout_ns);
            if (slot < 0) return SourceStatus::kTimeout;
            copy_staged(slot);
            has_staged = false;
            ready_slot = slot;
            ready_index = staged_index;
            return SourceStatus::kFrame;
        }
        if (ended) return SourceStatus::kEndOfStream;
        return is_dir ? fill_from_directory(timeout_ns) : fill_from_video(timeout_ns);
    }

    SourceStatus fill_from_directory(Nanos timeout_ns) {
        while (next_file < files.size()) {
            const std::size_t i = next_file++;
            if (!decode_image(files[i])) continue;
            has_staged = true;
            staged_index = static_cast<std::int64_t>(i);
            if (staged.cols != format.width || staged.rows != format.height) {
                format = bgr24_format(staged.cols, staged.rows);
                return SourceStatus::kFormatChange;  // delivered by the next call
            }
            return fill(timeout_ns);
        }
        ended = true;
        return SourceStatus::kEndOfStream;
    }

    SourceStatus fill_from_video(Nanos timeout_ns) {
        const int slot = acquire(timeout_ns);
        if (slot < 0) return SourceStatus::kTimeout;
        // Decode straight into the pool buffer: read() reuses a Mat of the right size
        // and type instead of allocating.
        cv::Mat m(format.height, format.width, CV_8UC3, pool.data(slot),
                  static_cast<std::size_t>(format.stride));
        std::uint8_t* const wanted = m.data;
        bool ok = false;
        try {
            ok = cap.read(m) && !m.empty();
        } catch (const cv::Exception& e) {
            warning = "decoding " + opt.path + " failed: " + e.what();
        }
        if (!ok && ++loops_done < opt.loops && next_video_index > 1) {
            // Play it again from the start (a soak); the index runs on.
            try {
                cap.release();
                ok = cap.open(opt.path, cv::CAP_FFMPEG) && cap.read(m) && !m.empty();
            } catch (const cv::Exception& e) {
                warning = "reopening " + opt.path + " failed: " + e.what();
            }
        }
        if (!ok) {
            pool.release(slot);
            end_video();
            return SourceStatus::kEndOfStream;
        }
        const std::int64_t index = next_video_index++;
        if (m.data != wanted) {
            // The decoder produced another size or layout: convert it outside the pool.
            const cv::Mat* bgr = nullptr;
            if (!to_bgr24(m, scratch, bgr)) {
                pool.release(slot);
                error = "video " + opt.path + ": frame " + std::to_string(index) +
                        " has an unsupported pixel layout";
                return SourceStatus::kError;
            }
            bgr->copyTo(staged);
            if (staged.cols != format.width || staged.rows != format.height) {
                pool.release(slot);
                has_staged = true;
                staged_index = index;
                format = bgr24_format(staged.cols, staged.rows);
                return SourceStatus::kFormatChange;
            }
            copy_staged(slot);
        }
        ready_slot = slot;
        ready_index = index;
        return SourceStatus::kFrame;
    }

    SourceStatus next(hal::Frame& out, Nanos timeout_ns) {
        if (!started) {
            error = "recording " + opt.path + ": next() before start()";
            return SourceStatus::kError;
        }
        if (ready_slot < 0) {
            const SourceStatus s = fill(timeout_ns);
            if (s != SourceStatus::kFrame) return s;
        }
        // Frame i is captured at t0 + i / fps, rounded to the ns (not i * rounded
        // period, which drifts); a virtual clock may already be past it.
        const Nanos due = t0 + static_cast<Nanos>(std::llround(static_cast<double>(ready_index) * 1e9 / fps));
        const Nanos now = clock.now();
        if (now < due) {
            if (!clock.is_virtual() && due - now > timeout_ns) {
                // Not due within the timeout: keep the frame for the next call.
                clock.sleep_until(now + std::max<Nanos>(timeout_ns, 0));
                return SourceStatus::kTimeout;
            }
            clock.sleep_until(due);
        }
        out.format = format;
        out.data = pool.data(ready_slot);
        out.capture_ns = due;
        out.sequence = static_cast<std::uint64_t>(ready_index);
        out.buffer_index = ready_slot;
        ready_slot = -1;
        ++read;
        return SourceStatus::kFrame;
    }
};

RecordedFrameSource::RecordedFrameSource(RecordedSourceOptions options, hal::Clock& clock)
    : impl_(std::make_unique<Impl>(std::move(options), clock)) {}

RecordedFrameSource::~RecordedFrameSource() = default;

bool RecordedFrameSource::open() {
    try {
        return impl_->open();
    } catch (const std::exception& e) {
        return impl_->fail("cannot open recording " + impl_->opt.path + ": " + e.what());
    }
}

bool RecordedFrameSource::start() {
    Impl& d = *impl_;
    if (d.started) return true;
    if (!d.opened && !open()) return false;
    const int n = std::max(1, d.opt.buffer_count);
    // Every buffer is allocated here, at the first format's size.
    if (!d.pool.allocate(n, d.format.size_bytes()))
        return d.fail("recording " + d.opt.path + ": cannot allocate " + std::to_string(n) +
                      " frame buffers");
    d.t0 = d.clock.now();
    d.loops_done = 0;
    d.started = true;
    return true;
}

void RecordedFrameSource::stop() {
    Impl& d = *impl_;
    // Lent buffers stay valid until the source is destroyed or started again; a new
    // start() replays from the first frame.
    d.cap.release();
    if (d.ready_slot >= 0) d.pool.release(d.ready_slot);
    d.ready_slot = -1;
    d.started = false;
    d.opened = false;
}

hal::SourceStatus RecordedFrameSource::next(hal::Frame& out, hal::Nanos timeout_ns) {
    try {
        return impl_->next(out, timeout_ns);
    } catch (const std::exception& e) {
        impl_->error = "recording " + impl_->opt.path + ": " + e.what();
        return SourceStatus::kError;
    }
}

void RecordedFrameSource::release(const hal::Frame& frame) {
    impl_->pool.release(frame.buffer_index);
}

hal::FrameFormat RecordedFrameSource::format() const {
    return impl_->format;
}
double RecordedFrameSource::frame_rate() const { return impl_->fps; }

hal::Nanos RecordedFrameSource::frame_period() const {
    return impl_->period;
}
int RecordedFrameSource::buffer_count() const {
    return std::max(1, impl_->opt.buffer_count);
}
const std::string& RecordedFrameSource::error() const {
    return impl_->error;
}
std::int64_t RecordedFrameSource::expected_frames() const {
    return impl_->expected;
}
std::int64_t RecordedFrameSource::frames_read() const {
    return impl_->read;
}
std::int64_t RecordedFrameSource::skipped_frames() const {
    return impl_->skipped;
}
bool RecordedFrameSource::truncated() const {
    return impl_->truncated;
}
const std::string& RecordedFrameSource::warning() const {
    return impl_->warning;
}

}  // namespace endotower::sim
