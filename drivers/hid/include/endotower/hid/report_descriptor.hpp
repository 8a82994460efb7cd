// HID report descriptor parsing and input-report decoding for the tool handle:
// pure code, no I/O. The handle's buttons (Button page 0x09, usages 1..8) and wheel
// (Generic Desktop 0x01, Wheel 0x38) are located by their usages in the descriptor
// (HID 1.11 section 6.2.2), with their report ID, bit offset and size, never by fixed
// byte offsets. Array (selector) button fields, absolute wheels and long items are
// not used; other usages are skipped.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <span>
#include <string>

#include "endotower/hal/control_input.hpp"

namespace endotower::hid {

constexpr int kMaxButtons = 8;
constexpr std::size_t kMaxReportBytes = 64;  // largest input report accepted (full-speed)

// One variable field of an input report.
struct ReportField {
    bool present = false;
    std::uint8_t report_id = 0;    // 0 when the descriptor has no report IDs
    std::uint16_t bit_offset = 0;  // from the first byte after the report ID
    std::uint8_t bit_size = 0;     // 1..32
    bool is_signed = false;        // logical minimum < 0
    bool relative = false;         // Input item's Relative flag
};

struct HandleLayout {
    bool numbered = false;                           // reports start with a report-ID byte
    std::array<ReportField, kMaxButtons> buttons{};  // [i] = Button usage i+1
    ReportField wheel;
    // Input report payload length in bytes per report ID (without the ID byte);
    // 0 = the ID carries no input report.
    std::array<std::uint16_t, 256> input_bytes{};
    int button_count() const;
};

// Parses `descriptor`. False with `error` (naming the item's byte offset) when it is
// malformed or has neither a button nor a wheel.
bool parse_report_descriptor(std::span<const std::uint8_t> descriptor, HandleLayout& out,
                             std::string& error);

enum class ReportStatus : std::uint8_t { kOk, kEmpty, kUnknownId, kShort, kOversized };
const char* to_string(ReportStatus s);

// Turns input reports into ControlEvents, keeping the previous button state.
class ReportDecoder {
public:
    explicit ReportDecoder(const HandleLayout& layout) : layout_(layout) {}

    // Decodes one report as read from hidraw (report-ID byte first when numbered).
    // Writes up to kMaxButtons + 1 events to `out` (press/release per changed
    // button, then the wheel delta), stamped `time_ns`; `count` says how many.
    // Rejected reports (status != kOk) change nothing.
    ReportStatus decode(std::span<const std::uint8_t> report, hal::Nanos time_ns,
                        std::array<hal::ControlEvent, kMaxButtons + 1>& out, int& count);
    // Releases every button still down (device gone): writes their release events,
    // returns how many.
    int release_all(hal::Nanos time_ns, std::array<hal::ControlEvent, kMaxButtons + 1>& out);

private:
    HandleLayout layout_;
    std::uint32_t buttons_ = 0;  // bit i = button i down
};

}  // namespace endotower::hid
