#include "endotower/v4l2/v4l2_capture.hpp"

#include <fcntl.h>
#include <linux/videodev2.h>
#include <poll.h>
#include <sys/ioctl.h>
#include <sys/mman.h>
#include <time.h>
#include <unistd.h>

#include <array>
#include <cmath>
#include <cstring>
#include <mutex>
#include <vector>

#include "endotower/system/syscall.hpp"
#include "endotower/v4l2/mjpeg_decoder.hpp"

namespace endotower::v4l2 {

namespace {
constexpr int kMaxBuffers = 16;

struct Buffer {
    void* data = MAP_FAILED;
    std::size_t length = 0;
    int dmabuf = -1;
    bool borrowed = false;
};

hal::Nanos monotonic_now() {
    timespec ts{};
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return ts.tv_sec * hal::kSecond + ts.tv_nsec;
}
}  // namespace

struct V4l2Capture::Impl {
    V4l2CaptureConfig config;
    int fd = -1;
    // The multi-planar API (HDMI receivers such as RK3588's hdmirx offer only it) with
    // one-buffer formats: the same frames, the plane's fields instead of the buffer's.
    std::uint32_t buf_type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
    bool mplane = false;
    std::array<Buffer, kMaxBuffers> buffers{};
    int count = 0;
    bool streaming = false;
    bool restart = false;  // format change seen: restart at the next next()
    bool dv = false;       // DV timings in use (HDMI receiver)
    std::string error;
    hal::FrameFormat fmt;
    hal::Nanos period = hal::kSecond / 60;
    CaptureStats stats;
    std::uint64_t last_seq = 0;
    bool have_seq = false;
    std::uint64_t seq_high = 0;  // extends the driver's 32-bit sequence
    int borrowed = 0;
    // MJPEG: buffer i is decoded into frame i of `decoded` (BGR24), lent instead of it.
    bool mjpeg = false;
    std::unique_ptr<MjpegDecoder> decoder;
    std::vector<std::uint8_t> decoded;
    mutable std::mutex mutex;  // release() may come from another thread

    bool fail(const char* call, int err) {
        error = system::errno_message(call, config.device, err);
        return false;
    }
    int xioctl(unsigned long req, void* arg) {
        return system::retry_eintr([&] { return ::ioctl(fd, req, arg); });
    }
    // A v4l2_buffer of our type and memory; `plane` receives the one plane (mplane).
    v4l2_buffer buffer_of(v4l2_plane& plane, int index = 0) const {
        v4l2_buffer b{};
        b.type = buf_type;
        b.memory = V4L2_MEMORY_MMAP;
        b.index = static_cast<std::uint32_t>(index);
        if (mplane) {
            plane = v4l2_plane{};
            b.m.planes = &plane;
            b.length = 1;
        }
        return b;
    }

    bool open_device() {
        fd = system::retry_eintr(
            [&] { return ::open(config.device.c_str(), O_RDWR | O_NONBLOCK | O_CLOEXEC); });
        if (fd < 0) return fail("open", errno);
        v4l2_capability cap{};
        if (xioctl(VIDIOC_QUERYCAP, &cap) < 0) return fail("VIDIOC_QUERYCAP", errno);
        const std::uint32_t caps =
            cap.capabilities & V4L2_CAP_DEVICE_CAPS ? cap.device_caps : cap.capabilities;
        mplane = !(caps & V4L2_CAP_VIDEO_CAPTURE) && (caps & V4L2_CAP_VIDEO_CAPTURE_MPLANE);
        buf_type = mplane ? V4L2_BUF_TYPE_VIDEO_CAPTURE_MPLANE : V4L2_BUF_TYPE_VIDEO_CAPTURE;
        if (!(caps & (V4L2_CAP_VIDEO_CAPTURE | V4L2_CAP_VIDEO_CAPTURE_MPLANE)) ||
            !(caps & V4L2_CAP_STREAMING)) {
            error = config.device + ": not a streaming video capture device (driver " +
                    reinterpret_cast<const char*>(cap.driver) + "); check capture.device";
            return false;
        }
        if (config.input >= 0) {
            int input = config.input;
            if (xioctl(VIDIOC_S_INPUT, &input) < 0) return fail("VIDIOC_S_INPUT", errno);
        }
        if (!config.dv_timings.empty()) {
            dv = true;
            // SOURCE_CHANGE events carry the input index as their id.
            int input = 0;
            if (xioctl(VIDIOC_G_INPUT, &input) < 0) input = 0;
            v4l2_event_subscription sub{};
            sub.type = V4L2_EVENT_SOURCE_CHANGE;
            sub.id = static_cast<std::uint32_t>(input);
            if (xioctl(VIDIOC_SUBSCRIBE_EVENT, &sub) < 0)
                return fail("VIDIOC_SUBSCRIBE_EVENT(SOURCE_CHANGE)", errno);
        }
        stats.present = true;
        return true;
    }

    // Sets the DV timings named in the board file, or the detected ones ("query").
    // False with stats.signal = false when the receiver sees no signal.
    bool set_dv_timings() {
        v4l2_dv_timings t{};
        if (config.dv_timings == "query") {
            if (xioctl(VIDIOC_QUERY_DV_TIMINGS, &t) < 0) {
                if (errno == ENOLINK || errno == ENOLCK || errno == ERANGE) {
                    stats.signal = false;
                    error = config.device +
                            ": no signal (VIDIOC_QUERY_DV_TIMINGS: " + std::strerror(errno) + ")";
                    return false;
                }
                return fail("VIDIOC_QUERY_DV_TIMINGS", errno);
            }
        } else {
            DvTimingsName want;
            if (!parse_dv_timings_name(config.dv_timings, want)) {
                error = config.device + ": capture.dv_timings '" + config.dv_timings +
                        "' is not 'query' nor like 1920x1080p60";
                return false;
            }
            bool found = false;
            double best = 1e9;
            for (std::uint32_t i = 0; i < 256; ++i) {
                v4l2_enum_dv_timings e{};
                e.index = i;
                if (xioctl(VIDIOC_ENUM_DV_TIMINGS, &e) < 0) break;
                const v4l2_bt_timings& bt = e.timings.bt;
                const bool il = bt.interlaced;
                const double hz = dv_refresh_hz(bt.pixelclock, V4L2_DV_BT_FRAME_WIDTH(&bt),
                                                V4L2_DV_BT_FRAME_HEIGHT(&bt)) *
                                  (il ? 2 : 1);
                if (dv_matches(want, bt.width, bt.height, il, hz) &&
                    std::fabs(hz - want.hz) < best) {
                    best = std::fabs(hz - want.hz);
                    t = e.timings;
                    found = true;
                }
            }
            if (!found) {
                error = config.device + ": the device lists no DV timings " + config.dv_timings +
                        " (VIDIOC_ENUM_DV_TIMINGS); see v4l2-ctl --list-dv-timings";
                return false;
            }
        }
        if (xioctl(VIDIOC_S_DV_TIMINGS, &t) < 0) return fail("VIDIOC_S_DV_TIMINGS", errno);
        config.width = static_cast<int>(t.bt.width);
        config.height = static_cast<int>(t.bt.height);
        const double hz = dv_refresh_hz(t.bt.pixelclock, V4L2_DV_BT_FRAME_WIDTH(&t.bt),
                                        V4L2_DV_BT_FRAME_HEIGHT(&t.bt));
        if (hz > 0) period = static_cast<hal::Nanos>(std::llround(1e9 / hz));
        stats.signal = true;
        return true;
    }

    bool set_format() {
        const CaptureFormatInfo& fi = info(config.format);
        if (!fi.supported) {
            error = config.device + ": " + std::string(fi.why);
            return false;
        }
        v4l2_format f{};
        f.type = buf_type;
        std::uint32_t width = 0, height = 0, fourcc = 0, stride = 0;
        if (mplane) {
            f.fmt.pix_mp.width = static_cast<std::uint32_t>(config.width);
            f.fmt.pix_mp.height = static_cast<std::uint32_t>(config.height);
            f.fmt.pix_mp.pixelformat = fi.fourcc;
            f.fmt.pix_mp.field = V4L2_FIELD_NONE;
            f.fmt.pix_mp.num_planes = 1;
            if (xioctl(VIDIOC_S_FMT, &f) < 0) return fail("VIDIOC_S_FMT", errno);
            width = f.fmt.pix_mp.width, height = f.fmt.pix_mp.height;
            fourcc = f.fmt.pix_mp.pixelformat, stride = f.fmt.pix_mp.plane_fmt[0].bytesperline;
            if (fourcc == fi.fourcc && f.fmt.pix_mp.num_planes != 1) {
                error = config.device + ": " + fourcc_name(fourcc) + " comes in " +
                        std::to_string(f.fmt.pix_mp.num_planes) +
                        " separate buffers here; the pipeline takes one-buffer frames";
                return false;
            }
        } else {
            f.fmt.pix.width = static_cast<std::uint32_t>(config.width);
            f.fmt.pix.height = static_cast<std::uint32_t>(config.height);
            f.fmt.pix.pixelformat = fi.fourcc;
            f.fmt.pix.field = V4L2_FIELD_NONE;
            if (xioctl(VIDIOC_S_FMT, &f) < 0) return fail("VIDIOC_S_FMT", errno);
            width = f.fmt.pix.width, height = f.fmt.pix.height;
            fourcc = f.fmt.pix.pixelformat, stride = f.fmt.pix.bytesperline;
        }
        if (fourcc != fi.fourcc) {
            error = config.device + ": does not offer " + fourcc_name(fi.fourcc) + " (it chose " +
                    fourcc_name(fourcc) + "); see v4l2-ctl --list-formats-ext";
            return false;
        }
        if (static_cast<int>(width) != config.width || static_cast<int>(height) != config.height) {
            error = config.device + ": cannot capture " + std::to_string(config.width) + "x" +
                    std::to_string(config.height) + " (it offers " + std::to_string(width) + "x" +
                    std::to_string(height) + ")";
            return false;
        }
        mjpeg = config.format == CaptureFormat::kMjpeg;
        if (mjpeg) stride = width * 3;  // the decoded frame's; the buffers hold JPEG
        fmt = {static_cast<int>(width), static_cast<int>(height), static_cast<int>(stride),
               fi.pixel};
        if (!dv && config.fps > 0) {
            v4l2_streamparm p{};
            p.type = buf_type;
            p.parm.capture.timeperframe = {
                1000, static_cast<std::uint32_t>(std::lround(config.fps * 1000))};
            if (xioctl(VIDIOC_S_PARM, &p) < 0 && errno != ENOTTY)
                return fail("VIDIOC_S_PARM", errno);
        }
        v4l2_streamparm p{};
        p.type = buf_type;
        if (!dv && xioctl(VIDIOC_G_PARM, &p) == 0 && p.parm.capture.timeperframe.denominator > 0)
            period = static_cast<hal::Nanos>(p.parm.capture.timeperframe.numerator) * hal::kSecond /
                     p.parm.capture.timeperframe.denominator;
        return true;
    }

    bool map_buffers() {
        v4l2_requestbuffers req{};
        req.count = static_cast<std::uint32_t>(config.buffers);
        req.type = buf_type;
        req.memory = V4L2_MEMORY_MMAP;
        if (xioctl(VIDIOC_REQBUFS, &req) < 0) return fail("VIDIOC_REQBUFS", errno);
        if (req.count < 2) {
            error = config.device + ": the driver granted " + std::to_string(req.count) +
                    " buffers, need 2";
            return false;
        }
        count = static_cast<int>(std::min<std::uint32_t>(req.count, kMaxBuffers));
        for (int i = 0; i < count; ++i) {
            v4l2_plane plane{};
            v4l2_buffer b = buffer_of(plane, i);
            if (xioctl(VIDIOC_QUERYBUF, &b) < 0) return fail("VIDIOC_QUERYBUF", errno);
            Buffer& buf = buffers[i];
            buf.length = mplane ? plane.length : b.length;
            buf.data = ::mmap(nullptr, buf.length, PROT_READ | PROT_WRITE, MAP_SHARED, fd,
                              mplane ? plane.m.mem_offset : b.m.offset);
            if (buf.data == MAP_FAILED) return fail("mmap", errno);
            v4l2_exportbuffer e{};
            e.type = buf_type;
            e.index = static_cast<std::uint32_t>(i);
            e.flags = O_RDONLY | O_CLOEXEC;
            // A driver without DMABUF export still captures; the display then copies.
            // MJPEG buffers hold JPEG, which no display takes: not exported.
            buf.dmabuf = !mjpeg && xioctl(VIDIOC_EXPBUF, &e) == 0 ? e.fd : -1;
            b = buffer_of(plane, i);
            if (xioctl(VIDIOC_QBUF, &b) < 0) return fail("VIDIOC_QBUF", errno);
        }
        if (mjpeg) {
            // Sized here, at start and at a format change (the decoder's arena then
            // resizes on the first frame).
            decoded.resize(static_cast<std::size_t>(count) * fmt.size_bytes());
            decoder = std::make_unique<MjpegDecoder>(config.device);
        }
        int type = static_cast<int>(buf_type);
        if (xioctl(VIDIOC_STREAMON, &type) < 0) return fail("VIDIOC_STREAMON", errno);
        streaming = true;
        have_seq = false;
        return true;
    }

    // Stops streaming and frees the buffers. Call only with no frame borrowed.
    void teardown(bool close_fd) {
        if (fd >= 0 && streaming) {
            int type = static_cast<int>(buf_type);
            xioctl(VIDIOC_STREAMOFF, &type);
        }
        streaming = false;
        for (int i = 0; i < count; ++i) {
            Buffer& b = buffers[i];
            if (b.data != MAP_FAILED) ::munmap(b.data, b.length);
            if (b.dmabuf >= 0) ::close(b.dmabuf);
            b = Buffer{};
        }
        count = 0;
        if (fd >= 0) {
            v4l2_requestbuffers req{};
            req.type = buf_type;
            req.memory = V4L2_MEMORY_MMAP;
            xioctl(VIDIOC_REQBUFS, &req);  // count 0 frees them in the driver
        }
        if (close_fd && fd >= 0) {
            ::close(fd);
            fd = -1;
        }
    }

    bool configure() {
        if (dv && !set_dv_timings()) return false;
        // Fixed timings are set whether or not the receiver sees a signal: ask it, so
        // that a capture started without one drops the receiver's noise (the no-signal
        // screen) until a SOURCE_CHANGE says the signal is there.
        stats.signal = !dv || receiver_locked();
        return set_format() && map_buffers();
    }

    // False only when the receiver says it has no signal (or cannot lock to it).
    bool receiver_locked() {
        v4l2_dv_timings t{};
        if (xioctl(VIDIOC_QUERY_DV_TIMINGS, &t) == 0) return true;
        return errno != ENOLINK && errno != ENOLCK && errno != ERANGE;
    }

    void device_gone() {
        stats.present = false;
        stats.signal = false;
        error = config.device + ": device gone; reopening";
        // The mappings of borrowed frames stay valid after close(); they are freed
        // in teardown() once given back. Freeing them now, when none is borrowed,
        // lets the kernel give the node's name to the device when it comes back.
        streaming = false;
        if (borrowed == 0) {
            teardown(true);
            return;
        }
        if (fd >= 0) ::close(fd);
        fd = -1;
    }

    bool requeue(int index) {
        v4l2_plane plane{};
        v4l2_buffer b = buffer_of(plane, index);
        return xioctl(VIDIOC_QBUF, &b) == 0;
    }

    // SOURCE_CHANGE: the receiver's timings changed. Same size: the signal is back;
    // another size: restart with what it now detects; none: no signal.
    void handle_events() {
        v4l2_event ev{};
        while (xioctl(VIDIOC_DQEVENT, &ev) == 0) {
            if (ev.type != V4L2_EVENT_SOURCE_CHANGE) continue;
            v4l2_dv_timings t{};
            if (xioctl(VIDIOC_QUERY_DV_TIMINGS, &t) < 0) {
                stats.signal = false;
                error = config.device + ": no signal";
                continue;
            }
            stats.signal = true;
            if (static_cast<int>(t.bt.width) != fmt.width ||
                static_cast<int>(t.bt.height) != fmt.height) {
                config.dv_timings = "query";
                restart = true;
            }
        }
    }

    hal::SourceStatus sleep_timeout(hal::Nanos timeout_ns) {
        timespec ts{static_cast<time_t>(timeout_ns / hal::kSecond),
                    static_cast<long>(timeout_ns % hal::kSecond)};
        while (::clock_nanosleep(CLOCK_MONOTONIC, 0, &ts, &ts) == EINTR) {
        }
        ++stats.timeouts;
        return hal::SourceStatus::kTimeout;
    }
};

V4l2Capture::V4l2Capture(V4l2CaptureConfig config) : impl_(std::make_unique<Impl>()) {
    impl_->config = std::move(config);
    impl_->error.reserve(512);  // per-frame messages (corrupt MJPEG) then fit without allocating
}

V4l2Capture::~V4l2Capture() {
    stop();
}

bool V4l2Capture::start() {
    Impl& m = *impl_;
    if (m.fd >= 0) return true;
    if (m.config.buffers < 2 || m.config.buffers > kMaxBuffers) {
        m.error = m.config.device + ": capture.buffers must be 2.." + std::to_string(kMaxBuffers);
        return false;
    }
    if (!m.open_device() || !m.configure()) {
        m.teardown(true);
        return false;
    }
    return true;
}

void V4l2Capture::stop() {
    std::lock_guard lock(impl_->mutex);
    impl_->teardown(true);
    impl_->borrowed = 0;
}

hal::SourceStatus V4l2Capture::next(hal::Frame& out, hal::Nanos timeout_ns) {
    Impl& m = *impl_;
    std::unique_lock lock(m.mutex);
    if (m.fd < 0 || m.restart) {
        // Reopen or restart only once every frame is back (their buffers are freed).
        if (m.borrowed > 0) {
            lock.unlock();
            return m.sleep_timeout(timeout_ns);
        }
        const hal::FrameFormat before = m.fmt;
        const bool reopen = m.fd < 0;
        m.teardown(reopen);
        m.restart = false;
        if ((reopen && !m.open_device()) || !m.configure()) {
            m.teardown(true);  // try again at the next call
            lock.unlock();
            return m.sleep_timeout(timeout_ns);
        }
        m.stats.reopens += reopen ? 1 : 0;
        if (!(m.fmt == before)) {
            ++m.stats.format_changes;
            return hal::SourceStatus::kFormatChange;
        }
    }
    const hal::Nanos deadline = monotonic_now() + timeout_ns;
    for (;;) {
        const hal::Nanos left = deadline - monotonic_now();
        if (left <= 0) {
            ++m.stats.timeouts;
            return hal::SourceStatus::kTimeout;
        }
        pollfd p{m.fd, POLLIN | POLLPRI, 0};
        const int fd = m.fd;
        lock.unlock();
        const int r = system::retry_eintr([&] {
            return ::poll(&p, 1,
                          static_cast<int>((left + hal::kMillisecond - 1) / hal::kMillisecond));
        });
        lock.lock();
        if (fd != m.fd) continue;  // stopped meanwhile
        if (r < 0) {
            m.fail("poll", errno);
            return hal::SourceStatus::kError;
        }
        if (r == 0) continue;
        if (p.revents & POLLPRI) {
            m.handle_events();
            if (m.restart) {
                ++m.stats.format_changes;
                return hal::SourceStatus::kFormatChange;
            }
        }
        if (p.revents & POLLERR) {
            // vb2 also says POLLERR when every buffer is borrowed: only ENODEV means gone.
            v4l2_capability cap{};
            if (m.xioctl(VIDIOC_QUERYCAP, &cap) < 0 && errno == ENODEV) {
                m.device_gone();
                ++m.stats.timeouts;
                return hal::SourceStatus::kTimeout;
            }
            if (m.borrowed == m.count) {
                lock.unlock();
                return m.sleep_timeout(deadline - monotonic_now() > 0 ? deadline - monotonic_now()
                                                                      : 0);
            }
        }
        if (!(p.revents & POLLIN)) continue;
        // Take every completed buffer; keep the newest, give the older ones back.
        v4l2_buffer newest{};
        std::uint32_t newest_used = 0, newest_offset = 0;  // JPEG bytes and where they start
        bool have = false;
        for (;;) {
            v4l2_plane plane{};
            v4l2_buffer b = m.buffer_of(plane);
            if (m.xioctl(VIDIOC_DQBUF, &b) < 0) {
                if (errno == EAGAIN) break;
                if (errno == ENODEV) {
                    m.device_gone();
                    ++m.stats.timeouts;
                    return hal::SourceStatus::kTimeout;
                }
                m.fail("VIDIOC_DQBUF", errno);
                return hal::SourceStatus::kError;
            }
            if (have) {
                m.requeue(static_cast<int>(newest.index));
                ++m.stats.skipped;
            }
            newest = b;
            newest_used = m.mplane ? plane.bytesused : b.bytesused;
            newest_offset = m.mplane ? plane.data_offset : 0;
            have = true;
        }
        if (!have) continue;
        const int index = static_cast<int>(newest.index);
        if ((newest.flags & V4L2_BUF_FLAG_ERROR) || (!m.stats.signal && m.dv)) {
            m.requeue(index);  // a damaged frame, or noise while there is no signal
            m.stats.corrupt += (newest.flags & V4L2_BUF_FLAG_ERROR) ? 1 : 0;
            continue;
        }
        // Sequence numbers are 32-bit in V4L2; extend them across wrap-around.
        std::uint64_t seq = (m.seq_high & ~0xffffffffull) | newest.sequence;
        if (m.have_seq && seq < m.last_seq) seq += 1ull << 32;
        if (m.have_seq && seq > m.last_seq + 1) m.stats.drops += seq - m.last_seq - 1;
        m.seq_high = seq;
        m.last_seq = seq;
        m.have_seq = true;
        auto* data = static_cast<std::uint8_t*>(m.buffers[index].data);
        if (m.mjpeg) {
            // Decoded under the lock (a few ms; the pipeline releases from this thread).
            std::uint8_t* frame =
                m.decoded.data() + static_cast<std::size_t>(index) * m.fmt.size_bytes();
            const std::size_t end = std::min<std::size_t>(newest_used, m.buffers[index].length);
            const std::size_t begin = std::min<std::size_t>(newest_offset, end);
            if (m.decoder->decode(data + begin, end - begin, seq, frame, m.fmt.width, m.fmt.height,
                                  m.fmt.stride) != MjpegResult::kDecoded) {
                m.requeue(index);  // like a flagged buffer: the video goes on with the next
                ++m.stats.corrupt;
                m.error = m.decoder->message();  // fits the reserved capacity
                continue;
            }
            data = frame;
        }
        out.data = data;
        out.format = m.fmt;
        out.sequence = seq;
        out.buffer_index = index;
        // The display scans it out without a copy (MJPEG: -1, the display copies).
        out.dmabuf_fd = m.buffers[index].dmabuf;
        const bool monotonic =
            (newest.flags & V4L2_BUF_FLAG_TIMESTAMP_MASK) == V4L2_BUF_FLAG_TIMESTAMP_MONOTONIC;
        out.capture_ns =
            monotonic ? newest.timestamp.tv_sec * hal::kSecond + newest.timestamp.tv_usec * 1000
                      : monotonic_now();
        m.buffers[index].borrowed = true;
        ++m.borrowed;
        ++m.stats.frames;
        return hal::SourceStatus::kFrame;
    }
}

void V4l2Capture::release(const hal::Frame& frame) {
    Impl& m = *impl_;
    std::lock_guard lock(m.mutex);
    const int i = frame.buffer_index;
    if (i < 0 || i >= m.count || !m.buffers[i].borrowed) return;
    m.buffers[i].borrowed = false;
    --m.borrowed;
    if (m.fd >= 0 && m.streaming) m.requeue(i);
}

hal::FrameFormat V4l2Capture::format() const {
    std::lock_guard lock(impl_->mutex);
    return impl_->fmt;
}
hal::Nanos V4l2Capture::frame_period() const {
    return impl_->period;
}
int V4l2Capture::buffer_count() const {
    return impl_->count > 0 ? impl_->count : impl_->config.buffers;
}
const std::string& V4l2Capture::error() const {
    return impl_->error;
}
int V4l2Capture::dmabuf_fd(int index) const {
    return index >= 0 && index < impl_->count ? impl_->buffers[index].dmabuf : -1;
}
const CaptureStats& V4l2Capture::stats() const {
    return impl_->stats;
}

}  // namespace endotower::v4l2
