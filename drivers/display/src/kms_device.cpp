#include "kms_device.hpp"

#include <drm_fourcc.h>
#include <fcntl.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <memory>

#include "endotower/hal/frame.hpp"
#include "endotower/system/syscall.hpp"

namespace endotower::display {

namespace {

struct ResDeleter {
    void operator()(drmModeRes* p) const { drmModeFreeResources(p); }
    void operator()(drmModeConnector* p) const { drmModeFreeConnector(p); }
    void operator()(drmModeEncoder* p) const { drmModeFreeEncoder(p); }
    void operator()(drmModePlaneRes* p) const { drmModeFreePlaneResources(p); }
    void operator()(drmModePlane* p) const { drmModeFreePlane(p); }
    void operator()(drmModeObjectProperties* p) const { drmModeFreeObjectProperties(p); }
    void operator()(drmModePropertyRes* p) const { drmModeFreeProperty(p); }
};
template <typename T>
using Ptr = std::unique_ptr<T, ResDeleter>;

// Property name -> id and current value of one KMS object.
struct Props {
    int fd;
    std::uint32_t object, type;
    std::uint32_t id(const char* name, std::uint64_t* value = nullptr) const {
        Ptr<drmModeObjectProperties> props(drmModeObjectGetProperties(fd, object, type));
        if (!props) return 0;
        for (std::uint32_t i = 0; i < props->count_props; ++i) {
            Ptr<drmModePropertyRes> p(drmModeGetProperty(fd, props->props[i]));
            if (p && std::strcmp(p->name, name) == 0) {
                if (value != nullptr) *value = props->prop_values[i];
                return p->prop_id;
            }
        }
        return 0;
    }
};

void fill_plane(int fd, const drmModePlane& p, PlaneInfo& out) {
    out.id = p.plane_id;
    out.formats.assign(p.formats, p.formats + p.count_formats);
    const Props pr{fd, p.plane_id, DRM_MODE_OBJECT_PLANE};
    out.fb_id = pr.id("FB_ID");
    out.crtc_id = pr.id("CRTC_ID");
    out.src_x = pr.id("SRC_X");
    out.src_y = pr.id("SRC_Y");
    out.src_w = pr.id("SRC_W");
    out.src_h = pr.id("SRC_H");
    out.crtc_x = pr.id("CRTC_X");
    out.crtc_y = pr.id("CRTC_Y");
    out.crtc_w = pr.id("CRTC_W");
    out.crtc_h = pr.id("CRTC_H");
}

std::string mode_list(const drmModeConnector& c) {
    std::string s;
    for (int i = 0; i < c.count_modes && i < 12; ++i) {
        char buf[64];
        std::snprintf(buf, sizeof buf, "%s%dx%d@%.2f", s.empty() ? "" : ", ", c.modes[i].hdisplay,
                      c.modes[i].vdisplay, mode_refresh(c.modes[i]));
        s += buf;
    }
    return s.empty() ? "none" : s;
}

}  // namespace

bool PlaneInfo::takes(std::uint32_t fourcc) const {
    return std::find(formats.begin(), formats.end(), fourcc) != formats.end();
}

std::string connector_name(const drmModeConnector& c) {
    const char* type = drmModeGetConnectorTypeName(c.connector_type);
    return std::string(type != nullptr ? type : "Unknown") + "-" +
           std::to_string(c.connector_type_id);
}

double mode_refresh(const drmModeModeInfo& m) {
    if (m.htotal == 0 || m.vtotal == 0) return m.vrefresh;
    return static_cast<double>(m.clock) * 1000.0 / (static_cast<double>(m.htotal) * m.vtotal);
}

std::uint32_t drm_fourcc(int f) {
    switch (static_cast<hal::PixelFormat>(f)) {
        case hal::PixelFormat::kBgr24:
            return DRM_FORMAT_RGB888;  // memory B G R
        case hal::PixelFormat::kRgb24:
            return DRM_FORMAT_BGR888;  // memory R G B
        case hal::PixelFormat::kBgra32:
            return DRM_FORMAT_XRGB8888;
        case hal::PixelFormat::kYuyv:
            return DRM_FORMAT_YUYV;
        case hal::PixelFormat::kUyvy:
            return DRM_FORMAT_UYVY;
        case hal::PixelFormat::kNv12:
            return DRM_FORMAT_NV12;
        case hal::PixelFormat::kGray8:
            return 0;  // R8 would show red
    }
    return 0;
}

bool KmsDevice::open(const std::string& path, const std::string& want, int width, int height,
                     double refresh_hz, bool want_atomic, std::string& error) {
    card = path;
    fd = system::retry_eintr([&] { return ::open(path.c_str(), O_RDWR | O_CLOEXEC); });
    if (fd < 0) {
        const int e = errno;
        error = system::errno_message("open", path, e);
        if (e == ENOENT)
            error +=
                ": no such display card; is the display driver loaded? (board file: display.card)";
        if (e == EACCES)
            error +=
                ": add the service user to the 'video' group (board/common/99-endotower.rules)";
        return false;
    }
    drmSetClientCap(fd, DRM_CLIENT_CAP_UNIVERSAL_PLANES, 1);
    atomic = want_atomic && drmSetClientCap(fd, DRM_CLIENT_CAP_ATOMIC, 1) == 0;
    // Writeback connectors are listed only to clients that ask for them.
    if (atomic) drmSetClientCap(fd, DRM_CLIENT_CAP_WRITEBACK_CONNECTORS, 1);
    std::uint64_t cap = 0;
    modifiers = drmGetCap(fd, DRM_CAP_ADDFB2_MODIFIERS, &cap) == 0 && cap != 0;

    Ptr<drmModeRes> res(drmModeGetResources(fd));
    if (!res) {
        error = system::errno_message("drmModeGetResources", path, errno) +
                ": not a KMS display device";
        return false;
    }
    std::string seen;
    Ptr<drmModeConnector> conn;
    for (int i = 0; i < res->count_connectors; ++i) {
        Ptr<drmModeConnector> c(drmModeGetConnector(fd, res->connectors[i]));
        if (!c) continue;
        const std::string name = display::connector_name(*c);
        if (c->connector_type == DRM_MODE_CONNECTOR_WRITEBACK) {
            const Props pr{fd, c->connector_id, DRM_MODE_OBJECT_CONNECTOR};
            wb_connector_id = c->connector_id;
            wb_crtc_prop = pr.id("CRTC_ID");
            wb_fb_prop = pr.id("WRITEBACK_FB_ID");
            wb_fence_prop = pr.id("WRITEBACK_OUT_FENCE_PTR");
            continue;
        }
        seen += (seen.empty() ? "" : ", ") + name +
                (c->connection == DRM_MODE_CONNECTED ? " (connected)" : " (disconnected)");
        if (conn) continue;
        if (want.empty() ? c->connection == DRM_MODE_CONNECTED : name == want) conn = std::move(c);
    }
    if (!conn) {
        error = path + ": " +
                (want.empty() ? "no connected monitor" : "no connector named '" + want + "'") +
                " (connectors: " + (seen.empty() ? "none" : seen) +
                "; board file: display.connector)";
        return false;
    }
    connector_id = conn->connector_id;
    connector_name = display::connector_name(*conn);
    if (conn->connection != DRM_MODE_CONNECTED || conn->count_modes == 0) {
        error = path + ": connector " + connector_name + " has no monitor connected; plug one in";
        return false;
    }
    // The requested size at the closest refresh rate; the preferred mode breaks ties.
    int best = -1;
    double best_diff = 1e9;
    for (int i = 0; i < conn->count_modes; ++i) {
        const drmModeModeInfo& m = conn->modes[i];
        if (m.hdisplay != width || m.vdisplay != height) continue;
        const double d = std::fabs(mode_refresh(m) - refresh_hz) -
                         ((m.type & DRM_MODE_TYPE_PREFERRED) ? 1e-3 : 0);
        if (d < best_diff) best_diff = d, best = i;
    }
    if (best < 0 || best_diff > 0.6) {
        char want_mode[64];
        std::snprintf(want_mode, sizeof want_mode, "%dx%d@%.2f", width, height, refresh_hz);
        error = path + ": connector " + connector_name + " has no mode " + want_mode +
                " (modes: " + mode_list(*conn) + "; board file: display.mode)";
        return false;
    }
    mode = conn->modes[best];

    // A CRTC that one of the connector's encoders can drive.
    for (int e = 0; e < conn->count_encoders && crtc_index < 0; ++e) {
        Ptr<drmModeEncoder> enc(drmModeGetEncoder(fd, conn->encoders[e]));
        if (!enc) continue;
        for (int i = 0; i < res->count_crtcs; ++i)
            if (enc->possible_crtcs & (1u << i)) {
                crtc_index = i;
                crtc_id = res->crtcs[i];
                break;
            }
    }
    if (crtc_index < 0) {
        error = path + ": no CRTC can drive connector " + connector_name;
        return false;
    }
    conn_crtc_prop = Props{fd, connector_id, DRM_MODE_OBJECT_CONNECTOR}.id("CRTC_ID");
    crtc_mode_prop = Props{fd, crtc_id, DRM_MODE_OBJECT_CRTC}.id("MODE_ID");
    crtc_active_prop = Props{fd, crtc_id, DRM_MODE_OBJECT_CRTC}.id("ACTIVE");

    Ptr<drmModePlaneRes> planes(drmModeGetPlaneResources(fd));
    for (std::uint32_t i = 0; planes && i < planes->count_planes; ++i) {
        Ptr<drmModePlane> p(drmModeGetPlane(fd, planes->planes[i]));
        if (!p || !(p->possible_crtcs & (1u << crtc_index))) continue;
        std::uint64_t type = 0;
        if (Props{fd, p->plane_id, DRM_MODE_OBJECT_PLANE}.id("type", &type) == 0) continue;
        PlaneInfo info;
        fill_plane(fd, *p, info);
        if (type == DRM_PLANE_TYPE_PRIMARY && primary.id == 0)
            primary = info;
        else if (type == DRM_PLANE_TYPE_OVERLAY && overlay.id == 0 &&
                 info.takes(DRM_FORMAT_ARGB8888))
            overlay = info;
    }
    if (primary.id == 0) {
        error = path + ": no primary plane for the CRTC of " + connector_name;
        return false;
    }
    if (overlay.id == 0) {
        error = path + ": no ARGB8888 overlay plane for the CRTC of " + connector_name +
                " (vkms: load it with enable_overlay=1)";
        return false;
    }
    return true;
}

void KmsDevice::close() {
    if (fd >= 0) ::close(fd);
    fd = -1;
}

bool KmsDevice::probe_connected() {
    Ptr<drmModeConnector> c(drmModeGetConnector(fd, connector_id));
    return c && c->connection == DRM_MODE_CONNECTED && c->count_modes > 0;
}

bool KmsDevice::connected_now() {
    // The connector's last known status without a probe and without allocating (this
    // runs once a second on the video thread): GETCONNECTOR with room for one mode is
    // what drmModeGetConnectorCurrent does, minus its mallocs; with count_modes 0 the
    // kernel would probe the monitor.
    drm_mode_modeinfo mode{};
    drm_mode_get_connector conn{};
    conn.connector_id = connector_id;
    conn.count_modes = 1;
    conn.modes_ptr = reinterpret_cast<std::uintptr_t>(&mode);
    // A failed read is not an unplug: the commit path finds real trouble.
    if (drmIoctl(fd, DRM_IOCTL_MODE_GETCONNECTOR, &conn) != 0) return true;
    return conn.connection != DRM_MODE_DISCONNECTED;
}

}  // namespace endotower::display
