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
    std::string tracker = "none";        // "none" | "kalman" | "kalman_red"
    double analysis_timeout_ms = 0.0;
    double analysis_virtual_cost_ms = 0.0;
    int max_overlay_age = 0;

    // display (drivers/display): display.card, .connector, .mode "WxH@HZ", .zero_copy, .atomic
    std::string display_card = "/dev/dri/card0";
    std::string display_connector;  // "" = the first connected
    int display_width = 1920, display_height = 1080;
    double display_refresh_hz = 60.0;
    bool display_zero_copy = true, display_atomic = true;
    double latency_budget_ms = 0.0;  // video.latency_budget_ms: capture -> flip limit; 0 = period + 2 ms

    // capture (drivers/v4l2): capture.device, .format, .width, .height, .fps, .buffers,
    // .input, .dv_timings (see v4l2_capture.hpp)
    bool has_capture = false;
    std::string capture_device = "/dev/video0", capture_format = "yuyv", capture_dv_timings;
    int capture_width = 1920, capture_height = 1080, capture_buffers = 4, capture_input = -1;
    double capture_fps = 0.0;
    // hid (drivers/hid): hid.vid, .pid (hex "0x1209" or decimal), .serial, .usage_page
    bool has_hid = false;
    int hid_vid = 0, hid_pid = 0, hid_usage_page = 0;
    std::string hid_serial;
    // gpio (drivers/gpio): gpio.chip, .line, .active_low, .debounce_ms, .long_press_ms
    bool has_gpio = false;
    std::string gpio_chip;
    int gpio_line = 0;
    bool gpio_active_low = false;
    double gpio_debounce_ms = 20.0, gpio_long_press_ms = 800.0;

    // paths: calibration, gesture_model (files checked by selftest), storage (a writable directory)
    std::string calibration, gesture_model, storage;

    // sim
    std::string sim_input, sim_events, sim_output, sim_frames, sim_trace;
    bool sim_realtime = false;
    double sim_fps = 0.0;  // 0 = the recording's own rate
};

bool load_board(const std::string& path, BoardConfig& out, std::string& error);

}  // namespace endotower::firmware
