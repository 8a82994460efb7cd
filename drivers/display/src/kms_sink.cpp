#include "endotower/display/kms_sink.hpp"

#include <EGL/egl.h>
#include <EGL/eglext.h>
#include <drm_fourcc.h>
#include <gbm.h>
#include <poll.h>
#include <sys/mman.h>
#include <time.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include "endotower/display/gles_overlay.hpp"
#include "endotower/system/syscall.hpp"
#include "kms_device.hpp"

namespace endotower::display {

namespace {

hal::Nanos mono_now() {
    timespec ts{};
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return static_cast<hal::Nanos>(ts.tv_sec) * hal::kSecond + ts.tv_nsec;
}

void log_line(const std::string& m) {
    std::fprintf(stderr, "endotower: display: %s\n", m.c_str());
}

// An XRGB8888 dumb buffer, mapped, with its framebuffer.
struct DumbBuffer {
    std::uint32_t handle = 0, fb = 0, pitch = 0;
    std::size_t size = 0;
    std::uint8_t* map = nullptr;

    bool create(int fd, int w, int h, std::string& error) {
        drm_mode_create_dumb c{};
        c.width = static_cast<std::uint32_t>(w);
        c.height = static_cast<std::uint32_t>(h);
        c.bpp = 32;
        if (drmIoctl(fd, DRM_IOCTL_MODE_CREATE_DUMB, &c) != 0) {
            error = system::errno_message("DRM_IOCTL_MODE_CREATE_DUMB",
                                          std::to_string(w) + "x" + std::to_string(h), errno);
            return false;
        }
        handle = c.handle;
        pitch = c.pitch;
        size = c.size;
        drm_mode_map_dumb m{};
        m.handle = handle;
        if (drmIoctl(fd, DRM_IOCTL_MODE_MAP_DUMB, &m) != 0) {
            error = system::errno_message("DRM_IOCTL_MODE_MAP_DUMB", "dumb buffer", errno);
            return false;
        }
        void* p = mmap(nullptr, size, PROT_READ | PROT_WRITE, MAP_SHARED, fd,
                       static_cast<off_t>(m.offset));
        if (p == MAP_FAILED) {
            error = system::errno_message("mmap", "dumb buffer", errno);
            return false;
        }
        map = static_cast<std::uint8_t*>(p);
        std::memset(map, 0, size);
        const std::uint32_t handles[4] = {handle}, pitches[4] = {pitch}, offsets[4] = {0};
        if (drmModeAddFB2(fd, c.width, c.height, DRM_FORMAT_XRGB8888, handles, pitches, offsets,
                          &fb, 0) != 0) {
            error = system::errno_message("drmModeAddFB2", "XRGB8888 dumb buffer", errno);
            return false;
        }
        return true;
    }
    void destroy(int fd) {
        if (fb != 0) drmModeRmFB(fd, fb);
        if (map != nullptr) munmap(map, size);
        if (handle != 0) {
            drm_mode_destroy_dumb d{};
            d.handle = handle;
            drmIoctl(fd, DRM_IOCTL_MODE_DESTROY_DUMB, &d);
        }
        *this = DumbBuffer{};
    }
};

// A DMABUF of the capture source, imported as a framebuffer.
struct Import {
    int dmabuf = -1;
    std::uint32_t handle = 0, fb = 0;
};

// The framebuffer of a GBM buffer, kept as the buffer's user data.
struct BoFb {
    int fd;
    std::uint32_t fb;
};
void destroy_bo_fb(gbm_bo*, void* data) {
    auto* f = static_cast<BoFb*>(data);
    if (f->fb != 0) drmModeRmFB(f->fd, f->fb);
    delete f;
}

// An atomic request in fixed arrays: drmModeAtomicCommit allocates, this does not.
// Properties must be added grouped by object.
struct AtomicRequest {
    std::array<std::uint32_t, 8> objs{}, counts{};
    std::array<std::uint32_t, 64> props{};
    std::array<std::uint64_t, 64> values{};
    std::uint32_t nobj = 0, nprop = 0;

    void clear() { nobj = nprop = 0; }
    void add(std::uint32_t obj, std::uint32_t prop, std::uint64_t value) {
        if (prop == 0 || nprop == props.size()) return;
        if (nobj == 0 || objs[nobj - 1] != obj) {
            if (nobj == objs.size()) return;
            objs[nobj] = obj;
            counts[nobj++] = 0;
        }
        props[nprop] = prop;
        values[nprop++] = value;
        ++counts[nobj - 1];
    }
    int commit(int fd, std::uint32_t flags, void* user) {
        drm_mode_atomic a{};
        a.flags = flags;
        a.count_objs = nobj;
        a.objs_ptr = reinterpret_cast<std::uint64_t>(objs.data());
        a.count_props_ptr = reinterpret_cast<std::uint64_t>(counts.data());
        a.props_ptr = reinterpret_cast<std::uint64_t>(props.data());
        a.prop_values_ptr = reinterpret_cast<std::uint64_t>(values.data());
        a.user_data = reinterpret_cast<std::uint64_t>(user);
        return drmIoctl(fd, DRM_IOCTL_MODE_ATOMIC, &a) == 0 ? 0 : -errno;
    }
};

constexpr int kMaxImports = 32;

}  // namespace

struct KmsSink::Impl {
    KmsSinkConfig cfg;
    hal::Clock& clock;
    KmsDevice dev;
    std::string error;
    KmsSinkStats stats;

    gbm_device* gbm = nullptr;
    gbm_surface* gsurf = nullptr;
    EGLDisplay egl_display = EGL_NO_DISPLAY;
    EGLContext egl_context = EGL_NO_CONTEXT;
    EGLSurface egl_surface = EGL_NO_SURFACE;
    std::unique_ptr<GlesOverlay> overlay;
    gbm_bo* shown_bo = nullptr;  // the overlay buffer on screen
    bool buffer_age = false;     // EGL_EXT_buffer_age

    hal::FrameFormat format;
    std::uint32_t fourcc = 0;
    bool zero_copy = false, zero_copy_checked = false;
    std::array<Import, kMaxImports> imports{};
    std::array<DumbBuffer, 2> copies{};
    int next_copy = 0;

    AtomicRequest req;
    std::uint32_t mode_blob = 0;
    bool modeset = true, connected = true;
    hal::Nanos next_probe = 0;
    // While connected, the connector's status is read once a second: some drivers (vkms,
    // many HDMI encoders) keep flipping into an unplugged connector.
    hal::Nanos next_status_check = 0;
    bool flip_done = false;
    hal::Nanos flip_ns = 0;

    DumbBuffer wb;
    bool wb_attached = false, wb_requested = false, wb_pending = false, wb_restore = false;
    int wb_fence = -1;

    Impl(KmsSinkConfig c, hal::Clock& k) : cfg(std::move(c)), clock(k) {}
    ~Impl();
    bool fail(const std::string& m) {
        error = m;
        return false;
    }
    bool setup_egl();
    void drop_imports();
    std::uint32_t import_fb(const hal::Frame& f);
    std::uint32_t copy_fb(const hal::Frame& f);
    std::uint32_t overlay_fb(gbm_bo* bo);
    void add_planes(std::uint32_t video_fb, int src_w, int src_h, std::uint32_t overlay_fb);
    int commit_atomic(std::uint32_t video_fb, int src_w, int src_h, std::uint32_t overlay_fb,
                      bool test_only);
    int commit_legacy(std::uint32_t video_fb, std::uint32_t overlay_fb);
    bool wait_flip();
    void lost_monitor(const std::string& why);
};

KmsSink::Impl::~Impl() {
    if (wb_fence >= 0) ::close(wb_fence);
    if (dev.fd >= 0) {
        drop_imports();
        for (DumbBuffer& b : copies) b.destroy(dev.fd);
        wb.destroy(dev.fd);
        if (mode_blob != 0) drmModeDestroyPropertyBlob(dev.fd, mode_blob);
    }
    if (egl_display != EGL_NO_DISPLAY) {
        eglMakeCurrent(egl_display, egl_surface, egl_surface, egl_context);
        overlay.reset();  // its GL objects need the context
        if (shown_bo != nullptr) gbm_surface_release_buffer(gsurf, shown_bo);
        eglMakeCurrent(egl_display, EGL_NO_SURFACE, EGL_NO_SURFACE, EGL_NO_CONTEXT);
        if (egl_surface != EGL_NO_SURFACE) eglDestroySurface(egl_display, egl_surface);
        if (egl_context != EGL_NO_CONTEXT) eglDestroyContext(egl_display, egl_context);
        eglTerminate(egl_display);
    }
    if (gsurf != nullptr) gbm_surface_destroy(gsurf);
    if (gbm != nullptr) gbm_device_destroy(gbm);
    dev.close();
}

bool KmsSink::Impl::setup_egl() {
    const int w = dev.mode.hdisplay, h = dev.mode.vdisplay;
    gbm = gbm_create_device(dev.fd);
    if (gbm == nullptr)
        return fail(dev.card + ": gbm_create_device failed (no GBM backend for this driver)");
    gsurf = gbm_surface_create(gbm, static_cast<std::uint32_t>(w), static_cast<std::uint32_t>(h),
                               GBM_FORMAT_ARGB8888, GBM_BO_USE_SCANOUT | GBM_BO_USE_RENDERING);
    if (gsurf == nullptr)
        return fail(dev.card + ": cannot create an ARGB8888 scanout surface with GBM");
    auto get_display = reinterpret_cast<PFNEGLGETPLATFORMDISPLAYEXTPROC>(
        eglGetProcAddress("eglGetPlatformDisplayEXT"));
    if (get_display == nullptr) return fail("EGL: no eglGetPlatformDisplayEXT");
    egl_display = get_display(EGL_PLATFORM_GBM_KHR, gbm, nullptr);
    if (egl_display == EGL_NO_DISPLAY || !eglInitialize(egl_display, nullptr, nullptr))
        return fail(dev.card + ": EGL cannot initialise on GBM");
    eglBindAPI(EGL_OPENGL_ES_API);
    const EGLint attribs[] = {EGL_SURFACE_TYPE,
                              EGL_WINDOW_BIT,
                              EGL_RED_SIZE,
                              8,
                              EGL_GREEN_SIZE,
                              8,
                              EGL_BLUE_SIZE,
                              8,
                              EGL_ALPHA_SIZE,
                              8,
                              EGL_RENDERABLE_TYPE,
                              EGL_OPENGL_ES2_BIT,
                              EGL_NONE};
    EGLConfig configs[64];
    EGLint n = 0;
    eglChooseConfig(egl_display, attribs, configs, 64, &n);
    EGLConfig config = nullptr;
    for (EGLint i = 0; i < n && config == nullptr; ++i) {
        EGLint id = 0;
        if (eglGetConfigAttrib(egl_display, configs[i], EGL_NATIVE_VISUAL_ID, &id) &&
            id == GBM_FORMAT_ARGB8888)
            config = configs[i];
    }
    if (config == nullptr) return fail("EGL: no ARGB8888 config for GBM");
    const EGLint ctx_attribs[] = {EGL_CONTEXT_CLIENT_VERSION, 2, EGL_NONE};
    egl_context = eglCreateContext(egl_display, config, EGL_NO_CONTEXT, ctx_attribs);
    egl_surface = eglCreateWindowSurface(egl_display, config,
                                         reinterpret_cast<EGLNativeWindowType>(gsurf), nullptr);
    if (egl_context == EGL_NO_CONTEXT || egl_surface == EGL_NO_SURFACE ||
        !eglMakeCurrent(egl_display, egl_surface, egl_surface, egl_context))
        return fail("EGL: cannot create a GLES2 context on the GBM surface");
    const char* ext = eglQueryString(egl_display, EGL_EXTENSIONS);
    buffer_age = ext != nullptr && std::strstr(ext, "EGL_EXT_buffer_age") != nullptr;
    overlay = std::make_unique<GlesOverlay>();
    if (!overlay->init(w, h, true)) return fail(overlay->error());
    return true;
}

void KmsSink::Impl::drop_imports() {
    for (Import& im : imports) {
        if (im.fb != 0) drmModeRmFB(dev.fd, im.fb);
        if (im.handle != 0) {
            drm_gem_close c{};
            c.handle = im.handle;
            drmIoctl(dev.fd, DRM_IOCTL_GEM_CLOSE, &c);
        }
        im = Import{};
    }
}

// The frame's DMABUF as a framebuffer, imported once per buffer; 0 if it cannot be.
std::uint32_t KmsSink::Impl::import_fb(const hal::Frame& f) {
    if (f.buffer_index < 0 || f.buffer_index >= kMaxImports || f.dmabuf_fd < 0) return 0;
    Import& im = imports[static_cast<std::size_t>(f.buffer_index)];
    if (im.fb != 0 && im.dmabuf == f.dmabuf_fd) return im.fb;
    std::uint32_t handle = 0;
    if (drmPrimeFDToHandle(dev.fd, f.dmabuf_fd, &handle) != 0) {
        log_line(system::errno_message("drmPrimeFDToHandle", dev.card, errno) +
                 "; copying frames instead");
        return 0;
    }
    std::uint32_t handles[4] = {handle}, pitches[4] = {static_cast<std::uint32_t>(f.format.stride)},
                  offsets[4] = {0};
    if (f.format.pixel_format == hal::PixelFormat::kNv12) {
        handles[1] = handle;
        pitches[1] = pitches[0];
        offsets[1] = pitches[0] * static_cast<std::uint32_t>(f.format.height);
    }
    std::uint32_t fb = 0;
    if (drmModeAddFB2(dev.fd, static_cast<std::uint32_t>(f.format.width),
                      static_cast<std::uint32_t>(f.format.height), fourcc, handles, pitches,
                      offsets, &fb, 0) != 0) {
        log_line(system::errno_message("drmModeAddFB2", "capture DMABUF", errno) +
                 "; copying frames instead");
        drm_gem_close c{};
        c.handle = handle;
        drmIoctl(dev.fd, DRM_IOCTL_GEM_CLOSE, &c);
        return 0;
    }
    im = Import{f.dmabuf_fd, handle, fb};
    return fb;
}

// The single CPU pass: convert the frame into the next dumb buffer, centred.
std::uint32_t KmsSink::Impl::copy_fb(const hal::Frame& f) {
    DumbBuffer& b = copies[static_cast<std::size_t>(next_copy)];
    next_copy ^= 1;
    const hal::Nanos t0 = mono_now();
    const int w = f.format.width, h = f.format.height;
    const int x0 = ((dev.mode.hdisplay - w) / 2) & ~1, y0 = (dev.mode.vdisplay - h) / 2;
    cv::Mat screen(dev.mode.vdisplay, dev.mode.hdisplay, CV_8UC4, b.map, b.pitch);
    cv::Mat dst = screen(cv::Rect(x0, y0, w, h));
    const std::size_t step = static_cast<std::size_t>(f.format.stride);
    switch (f.format.pixel_format) {
        case hal::PixelFormat::kYuyv:
            cv::cvtColor(cv::Mat(h, w, CV_8UC2, f.data, step), dst, cv::COLOR_YUV2BGRA_YUY2);
            break;
        case hal::PixelFormat::kUyvy:
            cv::cvtColor(cv::Mat(h, w, CV_8UC2, f.data, step), dst, cv::COLOR_YUV2BGRA_UYVY);
            break;
        case hal::PixelFormat::kNv12:
            cv::cvtColor(cv::Mat(h * 3 / 2, w, CV_8UC1, f.data, step), dst,
                         cv::COLOR_YUV2BGRA_NV12);
            break;
        case hal::PixelFormat::kBgr24:
            cv::cvtColor(cv::Mat(h, w, CV_8UC3, f.data, step), dst, cv::COLOR_BGR2BGRA);
            break;
        case hal::PixelFormat::kRgb24:
            cv::cvtColor(cv::Mat(h, w, CV_8UC3, f.data, step), dst, cv::COLOR_RGB2BGRA);
            break;
        case hal::PixelFormat::kGray8:
            cv::cvtColor(cv::Mat(h, w, CV_8UC1, f.data, step), dst, cv::COLOR_GRAY2BGRA);
            break;
        case hal::PixelFormat::kBgra32:
            cv::Mat(h, w, CV_8UC4, f.data, step).copyTo(dst);
            break;
    }
    const hal::Nanos dt = mono_now() - t0;
    stats.copy_ns_total += dt;
    stats.copy_ns_max = std::max(stats.copy_ns_max, dt);
    ++stats.copied_frames;
    return b.fb;
}

std::uint32_t KmsSink::Impl::overlay_fb(gbm_bo* bo) {
    if (auto* f = static_cast<BoFb*>(gbm_bo_get_user_data(bo))) return f->fb;
    const std::uint32_t w = gbm_bo_get_width(bo), h = gbm_bo_get_height(bo),
                        format = gbm_bo_get_format(bo);
    const std::uint64_t modifier = gbm_bo_get_modifier(bo);
    std::uint32_t handles[4] = {}, pitches[4] = {}, offsets[4] = {};
    std::uint64_t modifiers[4] = {};
    const int planes = std::min(gbm_bo_get_plane_count(bo), 4);
    for (int i = 0; i < planes; ++i) {
        handles[i] = gbm_bo_get_handle_for_plane(bo, i).u32;
        pitches[i] = gbm_bo_get_stride_for_plane(bo, i);
        offsets[i] = gbm_bo_get_offset(bo, i);
        modifiers[i] = modifier;
    }
    std::uint32_t fb = 0;
    int r = -1;
    if (dev.modifiers && modifier != DRM_FORMAT_MOD_INVALID)
        r = drmModeAddFB2WithModifiers(dev.fd, w, h, format, handles, pitches, offsets, modifiers,
                                       &fb, DRM_MODE_FB_MODIFIERS);
    // Mesa's kms_swrast reports an invalid modifier: the buffer is plain linear.
    if (r != 0) r = drmModeAddFB2(dev.fd, w, h, format, handles, pitches, offsets, &fb, 0);
    if (r != 0) {
        error = system::errno_message("drmModeAddFB2", "ARGB8888 overlay buffer", errno);
        return 0;
    }
    gbm_bo_set_user_data(bo, new BoFb{dev.fd, fb}, destroy_bo_fb);
    return fb;
}

void KmsSink::Impl::add_planes(std::uint32_t video_fb, int src_w, int src_h, std::uint32_t ofb) {
    const std::uint64_t mw = dev.mode.hdisplay, mh = dev.mode.vdisplay;
    const PlaneInfo& p = dev.primary;
    req.add(p.id, p.fb_id, video_fb);
    req.add(p.id, p.crtc_id, dev.crtc_id);
    req.add(p.id, p.src_x, 0);
    req.add(p.id, p.src_y, 0);
    req.add(p.id, p.src_w, static_cast<std::uint64_t>(src_w) << 16);
    req.add(p.id, p.src_h, static_cast<std::uint64_t>(src_h) << 16);
    req.add(p.id, p.crtc_x, 0);
    req.add(p.id, p.crtc_y, 0);
    req.add(p.id, p.crtc_w, mw);
    req.add(p.id, p.crtc_h, mh);
    const PlaneInfo& o = dev.overlay;
    req.add(o.id, o.fb_id, ofb);
    req.add(o.id, o.crtc_id, ofb != 0 ? dev.crtc_id : 0);
    if (ofb != 0) {
        req.add(o.id, o.src_x, 0);
        req.add(o.id, o.src_y, 0);
        req.add(o.id, o.src_w, mw << 16);
        req.add(o.id, o.src_h, mh << 16);
        req.add(o.id, o.crtc_x, 0);
        req.add(o.id, o.crtc_y, 0);
        req.add(o.id, o.crtc_w, mw);
        req.add(o.id, o.crtc_h, mh);
    }
}

// A readback commit gives the CRTC to the writeback connector alone: vkms in Linux
// 6.1 fails its clone check with the Virtual and Writeback encoders together. The
// next commit gives the CRTC back to the monitor.
int KmsSink::Impl::commit_atomic(std::uint32_t video_fb, int src_w, int src_h, std::uint32_t ofb,
                                 bool test_only) {
    req.clear();
    const bool readback = !test_only && wb_requested && wb_attached;
    const bool routing = modeset || readback || wb_restore;
    if (routing) {
        if (mode_blob == 0 &&
            drmModeCreatePropertyBlob(dev.fd, &dev.mode, sizeof dev.mode, &mode_blob) != 0)
            return -errno;
        req.add(dev.connector_id, dev.conn_crtc_prop, readback ? 0 : dev.crtc_id);
        req.add(dev.crtc_id, dev.crtc_mode_prop, mode_blob);
        req.add(dev.crtc_id, dev.crtc_active_prop, 1);
    }
    if (readback) {
        req.add(dev.wb_connector_id, dev.wb_crtc_prop, dev.crtc_id);
        req.add(dev.wb_connector_id, dev.wb_fb_prop, wb.fb);
        req.add(dev.wb_connector_id, dev.wb_fence_prop, reinterpret_cast<std::uint64_t>(&wb_fence));
    } else if (routing && dev.wb_connector_id != 0) {
        // Whoever had the card before may have left the writeback connector on the CRTC.
        req.add(dev.wb_connector_id, dev.wb_crtc_prop, 0);
    }
    add_planes(video_fb, src_w, src_h, ofb);
    std::uint32_t flags = routing ? DRM_MODE_ATOMIC_ALLOW_MODESET : DRM_MODE_ATOMIC_NONBLOCK;
    flags |= test_only ? DRM_MODE_ATOMIC_TEST_ONLY : DRM_MODE_PAGE_FLIP_EVENT;
    const int r = req.commit(dev.fd, flags, this);
    if (r == 0 && !test_only) {
        wb_restore = readback;
        if (readback) {
            wb_requested = false;
            wb_pending = true;
        }
    }
    return r;
}

int KmsSink::Impl::commit_legacy(std::uint32_t video_fb, std::uint32_t ofb) {
    if (modeset &&
        drmModeSetCrtc(dev.fd, dev.crtc_id, video_fb, 0, 0, &dev.connector_id, 1, &dev.mode) != 0)
        return -errno;
    const std::uint32_t w = dev.mode.hdisplay, h = dev.mode.vdisplay;
    if (drmModeSetPlane(dev.fd, dev.overlay.id, ofb != 0 ? dev.crtc_id : 0, ofb, 0, 0, 0,
                        ofb != 0 ? w : 0, ofb != 0 ? h : 0, 0, 0, ofb != 0 ? w << 16 : 0,
                        ofb != 0 ? h << 16 : 0) != 0)
        return -errno;
    return drmModePageFlip(dev.fd, dev.crtc_id, video_fb, DRM_MODE_PAGE_FLIP_EVENT, this) == 0
               ? 0
               : -errno;
}

namespace {
void on_flip(int, unsigned, unsigned sec, unsigned usec, void* user) {
    auto* m = static_cast<KmsSink::Impl*>(user);
    m->flip_done = true;
    m->flip_ns = static_cast<hal::Nanos>(sec) * hal::kSecond + static_cast<hal::Nanos>(usec) * 1000;
}
}  // namespace

// Waits for the page-flip event of the last commit: false after several periods.
bool KmsSink::Impl::wait_flip() {
    flip_done = false;
    drmEventContext ev{};
    ev.version = 2;
    ev.page_flip_handler = on_flip;
    const hal::Nanos period = static_cast<hal::Nanos>(1e9 / std::max(1.0, mode_refresh(dev.mode)));
    const hal::Nanos deadline =
        mono_now() + std::max<hal::Nanos>(5 * period, 250 * hal::kMillisecond);
    while (!flip_done) {
        const hal::Nanos left = deadline - mono_now();
        if (left <= 0) return false;
        pollfd p{dev.fd, POLLIN, 0};
        const int r = poll(&p, 1, static_cast<int>(left / hal::kMillisecond) + 1);
        if (r < 0 && errno != EINTR) return false;
        if (r > 0) drmHandleEvent(dev.fd, &ev);
    }
    return true;
}

void KmsSink::Impl::lost_monitor(const std::string& why) {
    if (!connected) return;
    connected = false;
    ++stats.disconnects;
    modeset = true;
    next_probe = mono_now() + hal::kSecond;
    log_line("connector " + dev.connector_name + ": " + why +
             "; dropping frames, probing once a second");
}

KmsSink::KmsSink(KmsSinkConfig config, hal::Clock& clock)
    : impl_(std::make_unique<Impl>(std::move(config), clock)) {}
KmsSink::~KmsSink() = default;

bool KmsSink::open() {
    Impl& m = *impl_;
    if (!m.dev.open(m.cfg.card, m.cfg.connector, m.cfg.width, m.cfg.height, m.cfg.refresh_hz,
                    m.cfg.atomic, m.error))
        return false;
    if (m.cfg.writeback && m.dev.atomic && m.dev.wb_connector_id != 0 && m.dev.wb_fb_prop != 0) {
        if (!m.wb.create(m.dev.fd, m.dev.mode.hdisplay, m.dev.mode.vdisplay, m.error)) return false;
        m.wb_attached = true;
    }
    return m.setup_egl();
}

bool KmsSink::configure(const hal::FrameFormat& format) {
    Impl& m = *impl_;
    if (m.dev.fd < 0) return m.fail("display not open");
    if (!format.valid()) return m.fail("display: invalid video format");
    if (format.width > m.dev.mode.hdisplay || format.height > m.dev.mode.vdisplay)
        return m.fail("display: video " + std::to_string(format.width) + "x" +
                      std::to_string(format.height) + " is larger than the mode " +
                      std::to_string(m.dev.mode.hdisplay) + "x" +
                      std::to_string(m.dev.mode.vdisplay) + " of " + m.dev.connector_name +
                      " (board file: display.mode)");
    m.format = format;
    m.fourcc = drm_fourcc(static_cast<int>(format.pixel_format));
    m.drop_imports();
    // Zero copy needs the plane to take the format at the mode's size (no scaling).
    m.zero_copy = m.cfg.zero_copy && m.fourcc != 0 && m.dev.primary.takes(m.fourcc) &&
                  format.width == m.dev.mode.hdisplay && format.height == m.dev.mode.vdisplay;
    m.zero_copy_checked = false;
    for (DumbBuffer& b : m.copies)
        if (b.fb == 0 && !b.create(m.dev.fd, m.dev.mode.hdisplay, m.dev.mode.vdisplay, m.error))
            return false;
    for (DumbBuffer& b : m.copies) std::memset(b.map, 0, b.size);  // black around a smaller frame
    return true;
}

hal::Nanos KmsSink::present(const hal::Frame& video, const hal::OverlayLayer* layer, hal::Nanos) {
    Impl& m = *impl_;
    ++m.stats.frames;
    if (!m.connected) {
        const hal::Nanos now = mono_now();
        // Probe once a second, not at every frame (a probe can take milliseconds).
        const bool due = now >= m.next_probe;
        if (due) m.next_probe = now + hal::kSecond;
        if (!due || !m.dev.probe_connected()) {
            ++m.stats.dropped_frames;
            return m.clock.now();
        }
        m.connected = true;
        ++m.stats.reconnects;
        log_line("connector " + m.dev.connector_name + " is back; setting the mode again");
    } else if (const hal::Nanos now = mono_now(); now >= m.next_status_check) {
        m.next_status_check = now + hal::kSecond;
        if (!m.dev.connected_now()) {
            m.lost_monitor("unplugged");
            ++m.stats.dropped_frames;
            return m.clock.now();
        }
    }

    // Video: the capture buffer itself when the driver takes it, else one copy.
    std::uint32_t video_fb = m.zero_copy ? m.import_fb(video) : 0;
    if (video_fb != 0 && !m.zero_copy_checked && m.dev.atomic) {
        const int r = m.commit_atomic(video_fb, video.format.width, video.format.height, 0, true);
        m.zero_copy_checked = true;
        if (r != 0) {
            log_line("the primary plane refuses the capture buffer (" +
                     std::string(std::strerror(-r)) + "); copying frames instead");
            m.zero_copy = false;
            video_fb = 0;
        }
    }
    const bool copied = video_fb == 0;
    if (copied)
        video_fb = m.copy_fb(video);
    else
        ++m.stats.zero_copy_frames;
    const int src_w = copied ? m.dev.mode.hdisplay : video.format.width;
    const int src_h = copied ? m.dev.mode.vdisplay : video.format.height;

    // Overlay: drawn with GLES2 into the next GBM buffer; an empty one turns the plane off.
    gbm_bo* bo = nullptr;
    std::uint32_t ofb = 0;
    if (layer != nullptr && !layer->empty()) {
        const hal::Nanos t0 = mono_now();
        EGLint age = 0;
        if (!m.buffer_age ||
            !eglQuerySurface(m.egl_display, m.egl_surface, EGL_BUFFER_AGE_EXT, &age))
            age = 0;
        if (!m.overlay->draw(layer, age)) {
            m.error = m.overlay->error();
            return -1;
        }
        eglSwapBuffers(m.egl_display, m.egl_surface);
        bo = gbm_surface_lock_front_buffer(m.gsurf);
        if (bo == nullptr) {
            m.error = "GBM: no overlay buffer to show (gbm_surface_lock_front_buffer)";
            return -1;
        }
        ofb = m.overlay_fb(bo);
        if (ofb == 0) {
            gbm_surface_release_buffer(m.gsurf, bo);
            return -1;
        }
        const hal::Nanos dt = mono_now() - t0;
        m.stats.overlay_ns_total += dt;
        m.stats.overlay_ns_max = std::max(m.stats.overlay_ns_max, dt);
        ++m.stats.overlay_frames;
    }

    const hal::Nanos committed = mono_now();
    int r = m.dev.atomic ? m.commit_atomic(video_fb, src_w, src_h, ofb, false)
                         : m.commit_legacy(video_fb, ofb);
    if (r != 0 && !copied) {
        // The driver took the test but not the flip: fall back to copying for good.
        m.zero_copy = false;
        video_fb = m.copy_fb(video);
        r = m.dev.atomic
                ? m.commit_atomic(video_fb, m.dev.mode.hdisplay, m.dev.mode.vdisplay, ofb, false)
                : m.commit_legacy(video_fb, ofb);
    }
    bool flipped = r == 0 && m.wait_flip();
    if (r == 0 && !flipped) ++m.stats.flip_timeouts;
    if (!flipped) {
        if (bo != nullptr) gbm_surface_release_buffer(m.gsurf, bo);
        if (!m.dev.probe_connected()) {
            m.lost_monitor(r != 0 ? "commit failed (" + std::string(std::strerror(-r)) +
                                        ") and no monitor"
                                  : "no page flip and no monitor");
            ++m.stats.dropped_frames;
            return m.clock.now();
        }
        m.error = r != 0 ? system::errno_message(
                               m.dev.atomic ? "DRM_IOCTL_MODE_ATOMIC" : "drmModePageFlip",
                               m.dev.card + " " + m.dev.connector_name, -r)
                         : m.dev.card + ": no page-flip event within 250 ms";
        return -1;
    }
    // vkms stamps the event of a mode set with the last vblank before it, which can
    // be long before the commit: then the event's arrival is the better time.
    if (m.modeset && m.flip_ns < committed) m.flip_ns = mono_now();
    m.modeset = false;
    // The previous overlay buffer is off the screen now.
    if (m.shown_bo != nullptr) gbm_surface_release_buffer(m.gsurf, m.shown_bo);
    m.shown_bo = bo;
    return m.flip_ns;
}

bool KmsSink::finish() {
    return true;
}
const std::string& KmsSink::error() const {
    return impl_->error;
}
std::string KmsSink::connector_name() const {
    return impl_->dev.connector_name;
}
std::string KmsSink::mode_name() const {
    char buf[64];
    const drmModeModeInfo& md = impl_->dev.mode;
    std::snprintf(buf, sizeof buf, "%dx%d@%.2f", md.hdisplay, md.vdisplay, mode_refresh(md));
    return buf;
}
hal::Nanos KmsSink::refresh_period() const {
    return static_cast<hal::Nanos>(1e9 / std::max(1.0, mode_refresh(impl_->dev.mode)));
}
bool KmsSink::atomic() const {
    return impl_->dev.atomic;
}
bool KmsSink::connected() const {
    return impl_->connected;
}
const KmsSinkStats& KmsSink::stats() const {
    return impl_->stats;
}

bool KmsSink::request_readback() {
    if (!impl_->wb_attached) return false;
    impl_->wb_requested = true;
    return true;
}

const std::uint8_t* KmsSink::readback(int& stride, hal::Nanos timeout_ns) {
    Impl& m = *impl_;
    if (!m.wb_pending) return nullptr;
    if (m.wb_fence >= 0) {
        pollfd p{m.wb_fence, POLLIN, 0};
        const int r = system::retry_eintr(
            [&] { return poll(&p, 1, static_cast<int>(timeout_ns / hal::kMillisecond)); });
        ::close(m.wb_fence);
        m.wb_fence = -1;
        if (r <= 0) return nullptr;
    }
    m.wb_pending = false;
    stride = static_cast<int>(m.wb.pitch);
    return m.wb.map;
}

}  // namespace endotower::display
