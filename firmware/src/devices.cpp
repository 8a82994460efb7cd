#include "devices.hpp"

#include <cstdio>

namespace endotower::firmware {

v4l2::V4l2CaptureConfig capture_config(const BoardConfig& b) {
    v4l2::V4l2CaptureConfig c;
    c.device = b.capture.device;
    v4l2::parse_capture_format(b.capture.format, c.format);  // validated by load_board
    c.width = b.capture.width;
    c.height = b.capture.height;
    c.fps = b.capture.fps;
    c.buffers = b.capture.buffers;
    c.input = b.capture.input;
    c.dv_timings = b.capture.dv_timings;
    return c;
}

display::KmsSinkConfig display_config(const BoardConfig& b) {
    display::KmsSinkConfig c;
    c.card = b.display_card;
    c.connector = b.display_connector;
    c.width = b.display_width;
    c.height = b.display_height;
    c.refresh_hz = b.display_refresh_hz;
    c.zero_copy = b.display_zero_copy;
    c.atomic = b.display_atomic;
    return c;
}

hid::HidHandleConfig handle_config(const BoardConfig& b) {
    hid::HidHandleConfig c;
    c.vid = static_cast<std::uint16_t>(b.handle.vid);
    c.pid = static_cast<std::uint16_t>(b.handle.pid);
    c.serial = b.handle.serial;
    c.usage_page = static_cast<std::uint16_t>(b.handle.usage_page);
    return c;
}

gpio::GpioButtonConfig button_config(const BoardConfig& b) {
    gpio::GpioButtonConfig c;
    c.chip = b.button.chip;
    c.line = static_cast<unsigned>(b.button.line);
    c.active_low = b.button.active_low;
    c.debounce.debounce_ns = static_cast<hal::Nanos>(b.button.debounce_ms * 1e6);
    c.debounce.long_press_ns = static_cast<hal::Nanos>(b.button.long_press_ms * 1e6);
    return c;
}

std::string device_fix(const std::string& e, const std::string& board) {
    auto has = [&](const char* s) { return e.find(s) != std::string::npos; };
    if (has("Permission denied") || has("(errno 13)"))
        return "run as the 'endotower' user or add yours to the 'endotower' group; install "
               "board/common/99-endotower.rules in /etc/udev/rules.d and run 'udevadm trigger'";
    if (has("Device or resource busy") || has("(errno 16)"))
        return "another program holds the device (a desktop session, a second endotower): stop it";
    if (has("No such file") || has("(errno 2)") || has("No such device") || has("(errno 19)"))
        return "check the device path in " + board + " and that its kernel driver is loaded";
    if (has("format") || has("not supported") || has("Invalid argument"))
        return "choose what the device offers in " + board +
               " (v4l2-ctl --list-formats-ext, --list-dv-timings; modetest -c for display modes)";
    if (has("connector") || has("monitor") || has("mode"))
        return "check the monitor cable and display.connector / display.mode in " + board;
    return "";
}

void print_device_error(const char* cmd, const std::string& error, const std::string& board) {
    std::fprintf(stderr, "endotower %s: %s\n", cmd, error.c_str());
    const std::string fix = device_fix(error, board);
    if (!fix.empty()) std::fprintf(stderr, "  fix: %s\n", fix.c_str());
}

}  // namespace endotower::firmware
