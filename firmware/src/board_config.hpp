// BoardConfig: one board's description (board/NAME/board.yaml), parsed with yaml-cpp.
// Relative paths are resolved against the board file's directory. Unknown keys are
// errors (a typo must not silently fall back to a default). Every error names the
// file, line and field.
#pragma once

#include <string>

namespace endotower::firmware {

struct BoardConfig {
    std::string path;  // the board file itself
    std::string name;
    std::string description;

    // video
    double latency_ms = 0.0;  // 0 = one frame period
    double compose_budget_ms = 0.0;
    double late_tolerance_ms = 0.0;  // 0 = 1 ms

    // analysis
    std::string stage = "status_badge";  // "status_badge" | "none"
    std::string tracker = "none";        // "none" | "kalman" | "kalman_red" | "likelihood" | vision::book_tracker_names()
    std::string tool_model;              // the likelihood tracker's model file
    double tool_diameter_mm = 5;         // shaft diameter for the 3-D pose (with a calibration)
    double analysis_timeout_ms = 0.0;
    double analysis_virtual_cost_ms = 0.0;
    int max_overlay_age = 0;
    // analysis.regions (docs/regions.md): the region tracker's settings
    std::string region_descriptor = "sift";  // "sift" | "orb" | "akaze"
    int region_redetect_interval = 10;       // frames; 0 = keyframe matching only when needed
    int region_min_inliers = 10;
    int region_detect_max_width = 640;
    bool region_propagate = true;
    // analysis.regions.overlay / depth_mm / media: what is anchored to each region
    // ("markers" | "image:PATH" | "object:cube"; docs/regions.md), the tissue's depth
    // when marked (the cube's scale), and the folder the images come from ("" = sci.media)
    std::string region_overlay = "markers";
    double region_depth_mm = 80;
    std::string region_media;

    // calibration: the scope's calibration file (endotower calibrate), "" = none
    std::string calibration;
    // analysis.gestures (issue 6): on when the map is present
    bool gestures = false;
    std::string gesture_model;  // a file of 'endotower train-gestures'
    // analysis.gestures.tool_model: the segmenter's pixel model; "" = analysis.tool_model
    std::string gesture_tool_model;
    // analysis.markers (issue 6): strip-marker tracking (docs/markers.md)
    bool markers = false;
    // analysis.fov_mask: with a calibration, blacken the analysis frame outside the field
    // of view (CalibrationStage, first in the chain): nothing is detected there
    bool fov_mask = true;
    // analysis.regions.mark_with_tool: the surgeon outlines regions with the tool tip
    // (RegionMarker; a long press starts). Not with sci: (the handle's button is its).
    bool region_mark_with_tool = false;
    double gesture_hold_ms = 1000.0;  // held still this long before it fires

    // sci: the surgeon-computer interface (issue 8, docs/sci.md); on when the map is present
    bool sci = false;
    std::string sci_layout = "three_level";  // "buttons" | "ring" | "three_level"
    double sci_dwell_ms = 2000, sci_activation_hold_ms = 3000, sci_cross_hold_ms = 1000,
           sci_confirm_ms = 2000;
    std::string sci_media;           // folder with ct/, xray/, mri/ image sub-folders
    std::string sci_patient_record;  // a text file, one line per record line

    // display (drivers/display): display.card, .connector, .mode "WxH@HZ", .zero_copy, .atomic
    std::string display_card = "/dev/dri/card0";
    std::string display_connector;  // "" = the first connected
    int display_width = 1920, display_height = 1080;
    double display_refresh_hz = 60.0;
    bool display_zero_copy = true, display_atomic = true;
    double latency_budget_ms =
        0.0;  // video.latency_budget_ms: capture -> flip limit; 0 = period + 2 ms

    // paths.storage: a writable directory (selftest checks it); the calibration file is the
    // top-level `calibration`, the gesture model `analysis.gestures.model`
    std::string storage;

    // sim
    std::string sim_input, sim_events, sim_output, sim_frames, sim_trace;
    bool sim_realtime = false;
    double sim_fps = 0.0;  // 0 = the recording's own rate

    // capture: (V4L2; drivers/v4l2). Absent: present = false.
    struct Capture {
        bool present = false;
        std::string device = "/dev/video0";
        std::string format = "yuyv";  // yuyv | uyvy | nv12 | bgrx | mjpeg (decoded to BGR24)
        int width = 1920, height = 1080;
        double fps = 0.0;  // 0 = the device's (or the DV timings') rate
        int buffers = 4;
        int input = -1;          // VIDIOC_S_INPUT; -1 = leave
        std::string dv_timings;  // "" | "query" | "1920x1080p60"
    } capture;
    // button: (GPIO through libgpiod; drivers/gpio)
    struct Button {
        bool present = false;
        std::string chip;  // gpiochip name, label, path or number
        int line = 0;
        bool active_low = false;
        double debounce_ms = 20.0;
        double long_press_ms = 800.0;  // 0 = no long press
    } button;
    // handle: (USB HID through hidapi; drivers/hid, drivers/usb)
    struct Handle {
        bool present = false;
        int vid = 0, pid = 0;  // 0x0000..0xffff, hex or decimal in the file
        std::string serial;    // "" = any
        int usage_page = 0;    // 0 = any
    } handle;
};

bool load_board(const std::string& path, BoardConfig& out, std::string& error);

}  // namespace endotower::firmware
