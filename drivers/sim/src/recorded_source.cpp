#include "endotower/sim/recorded_source.hpp"

#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <charconv>
#include <chrono>
#include <cmath>
#include <condition_variable>
#include <cstring>
#include <filesystem>
#include <mutex>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <opencv2/videoio.hpp>
#include <vector>

#include "endotower/system/syscall.hpp"

namespace endotower::sim {

namespace {

namespace fs = std::filesystem;
using hal::FrameFormat;
using hal::Nanos;
using hal::PixelFormat;
using hal::SourceStatus;

constexpr double kDefaultFps = 25.0;
constexpr double kMaxFps = 1000.0;  // above this a container's rate is nonsense

bool is_image_name(const fs::path& p) {
    std::string ext = p.extension().string();
    for (char& c : ext) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
    return ext == ".png" || ext == ".jpg" || ext == ".jpeg" || ext == ".bmp" || ext == ".tif" ||
           ext == ".tiff";
}

// Numbered frames sort by the last number in the stem ("frame_2" before "frame_10");
// names without a number follow in name order.
struct ImageName {
    bool numbered = false;
    std::uint64_t number = 0;
    std::string name;
    std::string path;
};

ImageName make_image_name(const fs::path& p) {
    ImageName n;
    n.name = p.filename().string();
    n.path = p.string();
    const std::string stem = p.stem().string();
    std::size_t end = stem.size();
    while (end > 0 && !std::isdigit(static_cast<unsigned char>(stem[end - 1]))) --end;
    std::size_t begin = end;
    while (begin > 0 && std::isdigit(static_cast<unsigned char>(stem[begin - 1]))) --begin;
    if (begin < end) {
        const auto r = std::from_chars(stem.data() + begin, stem.data() + end, n.number);
        n.numbered = r.ec == std::errc();
    }
    return n;
}

Nanos period_from_fps(double fps) {
    if (!std::isfinite(fps) || fps <= 0.0 || fps > kMaxFps) fps = kDefaultFps;
    return static_cast<Nanos>(std::llround(1e9 / fps));
}

// Brings any decoded image to 8-bit, 3-channel BGR. `scratch` keeps the converted
// pixels; returns false for layouts that have no sensible BGR reading.
bool to_bgr24(const cv::Mat& in, cv::Mat& scratch, const cv::Mat*& result) {
    if (in.empty()) return false;
    if (in.type() == CV_8UC3) {
        result = &in;
        return true;
    }
    const int cn = in.channels();
    if (cn != 1 && cn != 3 && cn != 4) return false;
    const cv::Mat* src = &in;
    cv::Mat depth8;
    if (in.depth() != CV_8U) {
        // 16-bit spans 0..65535, float images 0..1.
        const double scale = in.depth() == CV_16U   ? 1.0 / 257.0
                             : in.depth() >= CV_32F ? 255.0
                                                    : 1.0;
        in.convertTo(depth8, CV_8U, scale);
        src = &depth8;
    }
    if (cn == 1)
        cv::cvtColor(*src, scratch, cv::COLOR_GRAY2BGR);
    else if (cn == 4)
        cv::cvtColor(*src, scratch, cv::COLOR_BGRA2BGR);
    else
        src->copyTo(scratch);
    result = &scratch;
    return true;
}

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
    Nanos t0 = 0;
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

    // The pool. The outer vector is sized in start(); a slot's bytes are touched only
    // by the capture thread while the slot is not lent, so only `lent` needs the lock.
    std::vector<std::vector<std::uint8_t>> buffers;
    std::mutex mu;
    std::condition_variable freed;
    std::vector<char> lent;

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
        std::vector<ImageName> names;
        for (fs::directory_iterator it(opt.path, ec), end; !ec && it != end; it.increment(ec)) {
            const fs::path& p = it->path();
            // Hidden files include the FileSink's ".NAME.tmp.png" temporaries.
            if (p.filename().string().starts_with('.') || !is_image_name(p)) continue;
            std::error_code ec2;
            if (!it->is_regular_file(ec2)) continue;
            names.push_back(make_image_name(p));
        }
        if (ec) return fail("cannot list recording directory: " + opt.path + ": " + ec.message());
        if (names.empty()) return fail("no images (png/jpg/bmp/tif) in directory: " + opt.path);
        std::sort(names.begin(), names.end(), [](const ImageName& a, const ImageName& b) {
            if (a.numbered != b.numbered) return a.numbered;
            if (a.numbered && a.number != b.number) return a.number < b.number;
            return a.name < b.name;
        });
        files.reserve(names.size());
        for (ImageName& n : names) files.push_back(std::move(n.path));
        expected = static_cast<std::int64_t>(files.size());
        period = period_from_fps(opt.fps_override > 0.0 ? opt.fps_override : kDefaultFps);

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
        if (::access(opt.path.c_str(), R_OK) != 0)
            return fail("recording not readable: " +
                        system::errno_message("access", opt.path, errno));
        try {
            if (!cap.open(opt.path, cv::CAP_FFMPEG) || !cap.isOpened())
                return fail("cannot decode video: " + opt.path +
                            " (unsupported codec or not a video)");
            const double count = cap.get(cv::CAP_PROP_FRAME_COUNT);
            expected = std::isfinite(count) && count > 0 ? static_cast<std::int64_t>(count) : 0;
            period = period_from_fps(opt.fps_override > 0.0 ? opt.fps_override
                                                            : cap.get(cv::CAP_PROP_FPS));
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

    // A free slot, waiting (in real time) up to timeout_ns for a release(); -1 if none.
    int acquire(Nanos timeout_ns) {
        std::unique_lock lock(mu);
        auto find = [&] {
            for (std::size_t i = 0; i < lent.size(); ++i)
                if (!lent[i]) return static_cast<int>(i);
            return -1;
        };
        int slot = find();
        if (slot < 0 && timeout_ns > 0) {
            freed.wait_for(lock, std::chrono::nanoseconds(timeout_ns),
                           [&] { return (slot = find()) >= 0; });
        }
        if (slot < 0) return -1;
        lent[slot] = 1;
        lock.unlock();
        // Only a format change to a larger size grows a buffer.
        std::vector<std::uint8_t>& buf = buffers[slot];
        if (buf.size() < format.size_bytes()) buf.resize(format.size_bytes());
        return slot;
    }

    void give_back(int slot) {
        {
            std::lock_guard lock(mu);
            lent[slot] = 0;
        }
        freed.notify_one();
    }

    void copy_staged(int slot) {
        const cv::Mat& m = staged;
        std::uint8_t* dst = buffers[slot].data();
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
        cv::Mat m(format.height, format.width, CV_8UC3, buffers[slot].data(),
                  static_cast<std::size_t>(format.stride));
        std::uint8_t* const wanted = m.data;
        bool ok = false;
        try {
            ok = cap.read(m) && !m.empty();
        } catch (const cv::Exception& e) {
            warning = "decoding " + opt.path + " failed: " + e.what();
        }
        if (!ok) {
            give_back(slot);
            end_video();
            return SourceStatus::kEndOfStream;
        }
        const std::int64_t index = next_video_index++;
        if (m.data != wanted) {
            // The decoder produced another size or layout: convert it outside the pool.
            const cv::Mat* bgr = nullptr;
            if (!to_bgr24(m, scratch, bgr)) {
                give_back(slot);
                error = "video " + opt.path + ": frame " + std::to_string(index) +
                        " has an unsupported pixel layout";
                return SourceStatus::kError;
            }
            bgr->copyTo(staged);
            if (staged.cols != format.width || staged.rows != format.height) {
                give_back(slot);
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
        // Frame i is captured at t0 + i * period; a virtual clock may already be past it.
        const Nanos due = t0 + ready_index * period;
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
        out.data = buffers[ready_slot].data();
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
    try {
        // Every buffer is allocated here, at the first format's size.
        d.buffers.assign(static_cast<std::size_t>(n),
                         std::vector<std::uint8_t>(d.format.size_bytes()));
    } catch (const std::bad_alloc&) {
        return d.fail("recording " + d.opt.path + ": cannot allocate " + std::to_string(n) +
                      " frame buffers");
    }
    {
        std::lock_guard lock(d.mu);
        d.lent.assign(static_cast<std::size_t>(n), 0);
    }
    d.t0 = d.clock.now();
    d.started = true;
    return true;
}

void RecordedFrameSource::stop() {
    Impl& d = *impl_;
    // Lent buffers stay valid until the source is destroyed or started again; a new
    // start() replays from the first frame.
    d.cap.release();
    if (d.ready_slot >= 0) d.give_back(d.ready_slot);
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
    Impl& d = *impl_;
    {
        std::lock_guard lock(d.mu);
        const int i = frame.buffer_index;
        if (i < 0 || static_cast<std::size_t>(i) >= d.lent.size() || !d.lent[i]) return;
        d.lent[i] = 0;
    }
    d.freed.notify_one();
}

hal::FrameFormat RecordedFrameSource::format() const { return impl_->format; }
hal::Nanos RecordedFrameSource::frame_period() const { return impl_->period; }
int RecordedFrameSource::buffer_count() const { return std::max(1, impl_->opt.buffer_count); }
const std::string& RecordedFrameSource::error() const { return impl_->error; }
std::int64_t RecordedFrameSource::expected_frames() const { return impl_->expected; }
std::int64_t RecordedFrameSource::frames_read() const { return impl_->read; }
std::int64_t RecordedFrameSource::skipped_frames() const { return impl_->skipped; }
bool RecordedFrameSource::truncated() const { return impl_->truncated; }
const std::string& RecordedFrameSource::warning() const { return impl_->warning; }

}  // namespace endotower::sim
