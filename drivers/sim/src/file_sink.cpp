#include "endotower/sim/file_sink.hpp"

#include <fcntl.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstdio>
#include <filesystem>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <opencv2/videoio.hpp>
#include <vector>

#include "endotower/sim/compositor.hpp"
#include "endotower/system/syscall.hpp"

namespace endotower::sim {

namespace {

namespace fs = std::filesystem;
using hal::FrameFormat;
using hal::Nanos;
using hal::PixelFormat;

std::string describe(const FrameFormat& f) {
    return std::to_string(f.width) + 'x' + std::to_string(f.height) + ' ' +
           std::string(hal::to_string(f.pixel_format));
}

// The codec for a container, chosen by the file's extension.
bool fourcc_for(const std::string& ext, int& fourcc) {
    if (ext == ".mkv")
        fourcc = cv::VideoWriter::fourcc('F', 'F', 'V', '1');  // lossless
    else if (ext == ".avi")
        fourcc = cv::VideoWriter::fourcc('M', 'J', 'P', 'G');
    else if (ext == ".mp4")
        fourcc = cv::VideoWriter::fourcc('m', 'p', '4', 'v');
    else
        return false;
    return true;
}

// Writes all of `data` to `path`; false with errno set on failure.
bool write_all(const std::string& path, const std::vector<uchar>& data) {
    const int fd = system::retry_eintr(
        [&] { return ::open(path.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644); });
    if (fd < 0) return false;
    std::size_t done = 0;
    while (done < data.size()) {
        const ssize_t n = system::retry_eintr(
            [&] { return ::write(fd, data.data() + done, data.size() - done); });
        if (n < 0) {
            const int err = errno;
            ::close(fd);
            errno = err;
            return false;
        }
        done += static_cast<std::size_t>(n);
    }
    return ::close(fd) == 0;
}

}  // namespace

struct FileSink::Impl {
    FileSinkOptions opt;
    hal::Clock& clock;
    std::string error;

    bool prepared = false;  // output paths checked and directories created
    bool configured = false;
    FrameFormat format{};
    cv::Mat bgr;  // the composed picture, allocated by configure()
    std::int64_t written = 0;

    // Video: segment 0 is DIR/STEM.EXT, segment n is DIR/STEM.n.EXT, each written as
    // DIR/.STEM[.n].tmp.EXT (same extension, so FFmpeg picks the same container).
    std::string video_dir, video_stem, video_ext;
    int fourcc = 0;
    int segment = 0;
    std::string segment_path, segment_tmp;
    cv::VideoWriter writer;
    std::int64_t segment_frames = 0;

    // PNG frames: the paths are rewritten in place (reserved capacity, no allocation).
    std::string png_path, png_tmp;
    std::vector<uchar> png_bytes;
    const std::vector<int> png_params{cv::IMWRITE_PNG_COMPRESSION, 1};  // favour speed

    Impl(FileSinkOptions o, hal::Clock& c) : opt(std::move(o)), clock(c) {
        if (!(opt.fps > 0.0)) opt.fps = 25.0;
    }

    bool fail(std::string msg) {
        error = std::move(msg);
        return false;
    }

    bool prepare() {
        if (!opt.video_path.empty()) {
            const fs::path p(opt.video_path);
            video_ext = p.extension().string();
            video_stem = p.stem().string();
            video_dir = p.has_parent_path() ? p.parent_path().string() : std::string(".");
            if (!fourcc_for(video_ext, fourcc))
                return fail("cannot write video " + opt.video_path + ": unsupported extension '" +
                            video_ext + "' (use .mkv, .avi or .mp4)");
            std::error_code ec;
            fs::create_directories(video_dir, ec);
            if (ec)
                return fail("cannot write video " + opt.video_path + ": cannot create " +
                            video_dir + ": " + ec.message());
            if (::access(video_dir.c_str(), W_OK) != 0) {
                const int err = errno;  // before anything else can change it
                return fail("cannot write video " + opt.video_path + ": " +
                            system::errno_message("access", video_dir, err));
            }
        }
        if (!opt.frames_dir.empty()) {
            std::error_code ec;
            fs::create_directories(opt.frames_dir, ec);
            if (ec)
                return fail("cannot create frames directory " + opt.frames_dir + ": " +
                            ec.message());
            if (::access(opt.frames_dir.c_str(), W_OK) != 0) {
                const int err = errno;
                return fail("frames directory not writable: " +
                            system::errno_message("access", opt.frames_dir, err));
            }
            // Room for "/.NNNNNNNNNN.tmp.png" so that present() never allocates.
            png_path.reserve(opt.frames_dir.size() + 32);
            png_tmp.reserve(opt.frames_dir.size() + 32);
        }
        prepared = true;
        return true;
    }

    std::string segment_name(bool tmp) const {
        std::string name = tmp ? "." + video_stem : video_stem;
        if (segment > 0) name += '.' + std::to_string(segment);
        if (tmp) name += ".tmp";
        return (fs::path(video_dir) / (name + video_ext)).string();
    }

    bool open_segment() {
        segment_path = segment_name(false);
        segment_tmp = segment_name(true);
        bool ok = false;
        try {
            ok = writer.open(segment_tmp, cv::CAP_FFMPEG, fourcc, opt.fps,
                             cv::Size(format.width, format.height), true) &&
                 writer.isOpened();
        } catch (const cv::Exception&) {
            ok = false;
        }
        if (!ok) {
            ::unlink(segment_tmp.c_str());
            // FFmpeg does not say why; a directory that went away is the likelier cause.
            if (::access(video_dir.c_str(), W_OK) != 0) {
                const int err = errno;
                return fail("cannot write video " + segment_path + ": " +
                            system::errno_message("access", video_dir, err));
            }
            return fail("cannot write video " + segment_path + ": no encoder for " + video_ext +
                        " (FFmpeg could not open the writer)");
        }
        segment_frames = 0;
        return true;
    }

    // Closes the current segment and gives it its final name.
    bool close_segment() {
        if (!writer.isOpened()) return true;
        try {
            writer.release();
        } catch (const cv::Exception& e) {
            return fail("cannot finish video " + segment_path + ": " + e.what());
        }
        ++segment;  // a later frame starts the next segment, never overwrites this one
        segment_frames = 0;
        if (::rename(segment_tmp.c_str(), segment_path.c_str()) != 0) {
            const int err = errno;
            return fail("cannot finish video: " +
                        system::errno_message("rename", segment_tmp + " -> " + segment_path, err));
        }
        return true;
    }

    bool configure(const FrameFormat& f) {
        if (!f.valid()) return fail("file sink: invalid video format " + describe(f));
        if (!prepared && !prepare()) return false;
        if (configured && f == format) return true;
        // Frames of another size go to a new segment; the current one is complete.
        if (segment_frames > 0 && !close_segment()) return false;
        try {
            bgr.create(f.height, f.width, CV_8UC3);
        } catch (const cv::Exception& e) {
            return fail("file sink: cannot allocate " + describe(f) + ": " + e.what());
        }
        format = f;
        configured = true;
        return true;
    }

    // The video frame as BGR24 in `bgr`, with the overlay blended on top.
    bool compose_frame(const hal::Frame& video, const hal::OverlayLayer* overlay) {
        const FrameFormat& f = video.format;
        if (f.pixel_format == PixelFormat::kBgr24) {
            if (!sim::compose(video, overlay, bgr.data, static_cast<int>(bgr.step)))
                return fail("file sink: overlay does not match the " + describe(f) + " video");
            return true;
        }
        // Other formats: to BGR24 first (into the preallocated picture), then blend.
        const std::size_t step = static_cast<std::size_t>(f.stride);
        switch (f.pixel_format) {
            case PixelFormat::kBgra32:
                cv::cvtColor(cv::Mat(f.height, f.width, CV_8UC4, video.data, step), bgr,
                             cv::COLOR_BGRA2BGR);
                break;
            case PixelFormat::kRgb24:
                cv::cvtColor(cv::Mat(f.height, f.width, CV_8UC3, video.data, step), bgr,
                             cv::COLOR_RGB2BGR);
                break;
            case PixelFormat::kGray8:
                cv::cvtColor(cv::Mat(f.height, f.width, CV_8UC1, video.data, step), bgr,
                             cv::COLOR_GRAY2BGR);
                break;
            case PixelFormat::kYuyv:
                cv::cvtColor(cv::Mat(f.height, f.width, CV_8UC2, video.data, step), bgr,
                             cv::COLOR_YUV2BGR_YUYV);
                break;
            case PixelFormat::kUyvy:
                cv::cvtColor(cv::Mat(f.height, f.width, CV_8UC2, video.data, step), bgr,
                             cv::COLOR_YUV2BGR_UYVY);
                break;
            case PixelFormat::kNv12:
                cv::cvtColor(cv::Mat(f.height * 3 / 2, f.width, CV_8UC1, video.data, step), bgr,
                             cv::COLOR_YUV2BGR_NV12);
                break;
            case PixelFormat::kBgr24:
                break;
        }
        if (overlay == nullptr || overlay->empty()) return true;
        const FrameFormat out{f.width, f.height, static_cast<int>(bgr.step), PixelFormat::kBgr24};
        if (!blend_in_place(out, bgr.data, *overlay))
            return fail("file sink: overlay does not match the " + describe(f) + " video");
        return true;
    }

    bool write_png(std::int64_t index) {
        char name[32];
        std::snprintf(name, sizeof name, "%06lld.png", static_cast<long long>(index));
        png_path.assign(opt.frames_dir).append("/").append(name);
        std::snprintf(name, sizeof name, ".%06lld.tmp.png", static_cast<long long>(index));
        png_tmp.assign(opt.frames_dir).append("/").append(name);
        if (!cv::imencode(".png", bgr, png_bytes, png_params))
            return fail("cannot encode frame " + png_path + " as PNG");
        // Temporary file + rename: a crash never leaves a partial NNNNNN.png behind.
        if (!write_all(png_tmp, png_bytes)) {
            const int err = errno;
            ::unlink(png_tmp.c_str());
            return fail("cannot write frame: " + system::errno_message("write", png_tmp, err));
        }
        if (::rename(png_tmp.c_str(), png_path.c_str()) != 0) {
            const int err = errno;
            ::unlink(png_tmp.c_str());
            return fail("cannot write frame: " +
                        system::errno_message("rename", png_tmp + " -> " + png_path, err));
        }
        return true;
    }

    Nanos present(const hal::Frame& video, const hal::OverlayLayer* overlay, Nanos due_ns) {
        if (!configured) {
            error = "file sink: present() before configure()";
            return -1;
        }
        if (video.format != format || video.data == nullptr) {
            error = "file sink: frame " + describe(video.format) +
                    " does not match the configured " + describe(format);
            return -1;
        }
        if (!compose_frame(video, overlay)) return -1;
        if (!opt.video_path.empty()) {
            // Opened on the first frame so that a format change before any frame
            // leaves no empty file behind.
            if (!writer.isOpened() && !open_segment()) return -1;
            writer.write(bgr);
            ++segment_frames;
        }
        if (!opt.frames_dir.empty() && !write_png(written)) return -1;
        ++written;
        if (clock.now() < due_ns) clock.sleep_until(due_ns);
        return std::max(due_ns, clock.now());
    }
};

FileSink::FileSink(FileSinkOptions options, hal::Clock& clock)
    : impl_(std::make_unique<Impl>(std::move(options), clock)) {}

FileSink::~FileSink() {
    // Best effort: what was written so far is complete, so give it its final name.
    try {
        impl_->close_segment();
    } catch (...) {
    }
}

bool FileSink::configure(const hal::FrameFormat& format) {
    try {
        return impl_->configure(format);
    } catch (const std::exception& e) {
        return impl_->fail(std::string("file sink: ") + e.what());
    }
}

hal::Nanos FileSink::present(const hal::Frame& video, const hal::OverlayLayer* overlay,
                             hal::Nanos due_ns) {
    try {
        return impl_->present(video, overlay, due_ns);
    } catch (const std::exception& e) {
        impl_->error = std::string("file sink: ") + e.what();
        return -1;
    }
}

bool FileSink::finish() {
    try {
        return impl_->close_segment();
    } catch (const std::exception& e) {
        return impl_->fail(std::string("file sink: ") + e.what());
    }
}

const std::string& FileSink::error() const {
    return impl_->error;
}
std::int64_t FileSink::frames_written() const {
    return impl_->written;
}

}  // namespace endotower::sim
