// libFuzzer target: the HID report-descriptor parser and the report decoder, the
// two parsers of bytes a USB device sends. Input: 1 byte N, then N bytes of
// descriptor, then reports of 1..8 bytes (each preceded by its length byte).
#include <cstddef>
#include <cstdint>
#include <string>

#include "endotower/hid/report_descriptor.hpp"

using namespace endotower;

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    if (size == 0) return 0;
    const std::size_t n = data[0] < size - 1 ? data[0] : size - 1;
    hid::HandleLayout layout;
    std::string error;
    if (!hid::parse_report_descriptor({data + 1, n}, layout, error)) {
        if (error.rfind("HID report descriptor, byte ", 0) != 0) __builtin_trap();
        return 0;
    }
    if (layout.button_count() == 0 && !layout.wheel.present) __builtin_trap();
    hid::ReportDecoder decoder(layout);
    std::array<hal::ControlEvent, hid::kMaxButtons + 1> events;
    std::size_t i = 1 + n;
    while (i < size) {
        const std::size_t len = data[i] % (hid::kMaxReportBytes + 3);
        ++i;
        const std::size_t take = len < size - i ? len : size - i;
        int count = -1;
        const auto s = decoder.decode({data + i, take}, 0, events, count);
        if (count < 0 || count > hid::kMaxButtons + 1) __builtin_trap();
        if (s != hid::ReportStatus::kOk && count != 0) __builtin_trap();
        i += take;
    }
    return 0;
}
