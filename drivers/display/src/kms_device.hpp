// KmsDevice: what KmsSink finds on a DRM card: connector, mode, CRTC, planes and the
// property ids an atomic commit needs. Internal to drivers/display.
#pragma once

#include <xf86drm.h>
#include <xf86drmMode.h>

#include <cstdint>
#include <string>
#include <vector>

namespace endotower::display {

struct PlaneInfo {
    std::uint32_t id = 0;
    std::vector<std::uint32_t> formats;
    // Property ids (0: absent).
    std::uint32_t fb_id = 0, crtc_id = 0, src_x = 0, src_y = 0, src_w = 0, src_h = 0;
    std::uint32_t crtc_x = 0, crtc_y = 0, crtc_w = 0, crtc_h = 0;
    bool takes(std::uint32_t fourcc) const;
};

struct KmsDevice {
    int fd = -1;
    std::string card;
    bool atomic = false;
    bool modifiers = false;  // DRM_CAP_ADDFB2_MODIFIERS
    std::uint32_t connector_id = 0, crtc_id = 0;
    int crtc_index = -1;
    std::string connector_name;
    drmModeModeInfo mode{};
    std::uint32_t conn_crtc_prop = 0, crtc_mode_prop = 0, crtc_active_prop = 0;
    PlaneInfo primary, overlay;
    // Writeback connector (vkms): 0 when there is none.
    std::uint32_t wb_connector_id = 0, wb_crtc_prop = 0, wb_fb_prop = 0, wb_fence_prop = 0;

    // Opens `card` and picks connector `want` ("" = first connected) with the mode
    // closest to width x height @ refresh_hz. False with `error` naming what is wrong.
    bool open(const std::string& card, const std::string& want, int width, int height,
              double refresh_hz, bool want_atomic, std::string& error);
    void close();
    // Re-reads the connector (a probe): true when a monitor is attached.
    bool probe_connected();
    // The connector's last known status, without probing (the kernel updates it on a
    // hotplug interrupt or its own polling): cheap enough to ask every second.
    bool connected_now();
};

std::string connector_name(const drmModeConnector& c);
double mode_refresh(const drmModeModeInfo& m);
// The DRM fourcc for a hal pixel format, 0 if it has none.
std::uint32_t drm_fourcc(int hal_pixel_format);

}  // namespace endotower::display
