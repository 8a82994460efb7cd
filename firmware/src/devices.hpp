// Devices: the driver configurations a board file gives for `run` and `selftest`,
// and the fix to print with a device error ("endotower run: ERROR\n  fix: FIX").
#pragma once

#include <string>

#include "board_config.hpp"
#include "endotower/display/kms_sink.hpp"
#include "endotower/gpio/gpio_button.hpp"
#include "endotower/hid/hid_handle.hpp"
#include "endotower/v4l2/v4l2_capture.hpp"

namespace endotower::firmware {

v4l2::V4l2CaptureConfig capture_config(const BoardConfig& b);
display::KmsSinkConfig display_config(const BoardConfig& b);
hid::HidHandleConfig handle_config(const BoardConfig& b);
gpio::GpioButtonConfig button_config(const BoardConfig& b);

// What to do about a device error, from its errno text; "" when there is no advice.
// `board` is the board file (for "edit BOARD: capture.device").
std::string device_fix(const std::string& error, const std::string& board);

// Prints "endotower CMD: ERROR" and, when known, "  fix: ...".
void print_device_error(const char* cmd, const std::string& error, const std::string& board);

}  // namespace endotower::firmware
