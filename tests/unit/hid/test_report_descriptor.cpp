// The HID report-descriptor parser and report decoder, on descriptors with known
// layouts (handle_descriptors.hpp) and on malformed ones.
#include <gtest/gtest.h>

#include <vector>

#include "endotower/hid/report_descriptor.hpp"
#include "handle_descriptors.hpp"

namespace endotower::hid {
namespace {

using Kind = hal::ControlEvent::Kind;
using Events = std::array<hal::ControlEvent, kMaxButtons + 1>;

HandleLayout parse_ok(std::span<const std::uint8_t> d) {
    HandleLayout l;
    std::string error;
    EXPECT_TRUE(parse_report_descriptor(d, l, error)) << error;
    return l;
}

std::string parse_error(std::vector<std::uint8_t> d) {
    HandleLayout l;
    std::string error;
    EXPECT_FALSE(parse_report_descriptor(d, l, error));
    return error;
}

TEST(ReportDescriptor, HandleWithReportIdsLocatesButtonsAndWheel) {
    const HandleLayout l = parse_ok(testing::kHandleDescriptor);
    EXPECT_TRUE(l.numbered);
    EXPECT_EQ(l.button_count(), 3);
    for (int b = 0; b < 3; ++b) {
        EXPECT_EQ(l.buttons[b].report_id, 1);
        EXPECT_EQ(l.buttons[b].bit_offset, b);
        EXPECT_EQ(l.buttons[b].bit_size, 1);
    }
    EXPECT_FALSE(l.buttons[3].present);
    ASSERT_TRUE(l.wheel.present);
    EXPECT_EQ(l.wheel.report_id, 1);
    EXPECT_EQ(l.wheel.bit_offset, 24);  // after 3 buttons + 5 padding + X + Y
    EXPECT_EQ(l.wheel.bit_size, 8);
    EXPECT_TRUE(l.wheel.is_signed);
    EXPECT_TRUE(l.wheel.relative);
    EXPECT_EQ(l.input_bytes[1], 4);
    EXPECT_EQ(l.input_bytes[2], 2);
    EXPECT_EQ(l.input_bytes[0], 0);
    EXPECT_EQ(l.input_bytes[3], 0);
}

TEST(ReportDescriptor, OddLayoutWithoutReportIds) {
    const HandleLayout l = parse_ok(testing::kOddLayoutDescriptor);
    EXPECT_FALSE(l.numbered);
    EXPECT_EQ(l.wheel.bit_offset, 4);
    EXPECT_EQ(l.wheel.bit_size, 12);
    EXPECT_EQ(l.buttons[1].bit_offset, 16);  // usage 2 comes first
    EXPECT_EQ(l.buttons[0].bit_offset, 17);
    EXPECT_EQ(l.input_bytes[0], 3);
}

TEST(ReportDecoder, PressReleaseAndScrollFromHandleReports) {
    ReportDecoder dec(parse_ok(testing::kHandleDescriptor));
    Events ev;
    int n = -1;
    const std::uint8_t press[] = {1, 0x01, 5, 0xfb, 0};
    ASSERT_EQ(dec.decode(press, 100, ev, n), ReportStatus::kOk);
    ASSERT_EQ(n, 1);
    EXPECT_EQ(ev[0].kind, Kind::kButtonPress);
    EXPECT_EQ(ev[0].button, 0);
    EXPECT_EQ(ev[0].time_ns, 100);
    ASSERT_EQ(dec.decode(press, 110, ev, n), ReportStatus::kOk);
    EXPECT_EQ(n, 0);                                           // still down: no new event
    const std::uint8_t scroll_down[] = {1, 0x05, 0, 0, 0xff};  // button 3 too, wheel -1
    ASSERT_EQ(dec.decode(scroll_down, 120, ev, n), ReportStatus::kOk);
    ASSERT_EQ(n, 2);
    EXPECT_EQ(ev[0].kind, Kind::kButtonPress);
    EXPECT_EQ(ev[0].button, 2);
    EXPECT_EQ(ev[1].kind, Kind::kWheel);
    EXPECT_EQ(ev[1].delta, -1);
    const std::uint8_t up[] = {1, 0x00, 0, 0, 3};
    ASSERT_EQ(dec.decode(up, 130, ev, n), ReportStatus::kOk);
    ASSERT_EQ(n, 3);
    EXPECT_EQ(ev[0].kind, Kind::kButtonRelease);
    EXPECT_EQ(ev[0].button, 0);
    EXPECT_EQ(ev[1].kind, Kind::kButtonRelease);
    EXPECT_EQ(ev[1].button, 2);
    EXPECT_EQ(ev[2].delta, 3);
    const std::uint8_t consumer[] = {2, 0xe9, 0x00};
    EXPECT_EQ(dec.decode(consumer, 140, ev, n), ReportStatus::kOk);
    EXPECT_EQ(n, 0);
}

TEST(ReportDecoder, MalformedReportsRejectedWithoutStateChange) {
    ReportDecoder dec(parse_ok(testing::kHandleDescriptor));
    Events ev;
    int n = -1;
    const std::uint8_t short_r[] = {1, 0x01, 0, 0};
    const std::uint8_t long_r[] = {1, 0x01, 0, 0, 0, 0};
    const std::uint8_t unknown[] = {3, 0x01, 0, 0, 0};
    const std::uint8_t zero_id[] = {0, 0x01, 0, 0, 0};
    EXPECT_EQ(dec.decode(short_r, 1, ev, n), ReportStatus::kShort);
    EXPECT_EQ(dec.decode(long_r, 1, ev, n), ReportStatus::kOversized);
    EXPECT_EQ(dec.decode(unknown, 1, ev, n), ReportStatus::kUnknownId);
    EXPECT_EQ(dec.decode(zero_id, 1, ev, n), ReportStatus::kUnknownId);
    EXPECT_EQ(dec.decode({}, 1, ev, n), ReportStatus::kEmpty);
    EXPECT_EQ(n, 0);
    const std::uint8_t press[] = {1, 0x01, 0, 0, 0};
    ASSERT_EQ(dec.decode(press, 2, ev, n), ReportStatus::kOk);
    EXPECT_EQ(n, 1);  // the rejected reports did not count as a press
}

TEST(ReportDecoder, TwelveBitWheelAndSwappedButtons) {
    ReportDecoder dec(parse_ok(testing::kOddLayoutDescriptor));
    Events ev;
    int n = -1;
    // wheel = 0xffb (-5) at bits 4..15; bit 17 = Button usage 1 (index 0).
    const std::uint8_t r[] = {0xb0, 0xff, 0x02};
    ASSERT_EQ(dec.decode(r, 7, ev, n), ReportStatus::kOk);
    ASSERT_EQ(n, 2);
    EXPECT_EQ(ev[0].kind, Kind::kButtonPress);
    EXPECT_EQ(ev[0].button, 0);
    EXPECT_EQ(ev[1].kind, Kind::kWheel);
    EXPECT_EQ(ev[1].delta, -5);
    const std::uint8_t r2[] = {0x50, 0x00, 0x01};  // wheel +5, usage 2 down, usage 1 up
    ASSERT_EQ(dec.decode(r2, 8, ev, n), ReportStatus::kOk);
    ASSERT_EQ(n, 3);
    EXPECT_EQ(ev[0].kind, Kind::kButtonRelease);
    EXPECT_EQ(ev[0].button, 0);
    EXPECT_EQ(ev[1].kind, Kind::kButtonPress);
    EXPECT_EQ(ev[1].button, 1);
    EXPECT_EQ(ev[2].delta, 5);
}

TEST(ReportDecoder, ReleaseAllAfterUnplug) {
    ReportDecoder dec(parse_ok(testing::kHandleDescriptor));
    Events ev;
    int n = 0;
    const std::uint8_t press[] = {1, 0x03, 0, 0, 0};
    ASSERT_EQ(dec.decode(press, 1, ev, n), ReportStatus::kOk);
    ASSERT_EQ(dec.release_all(9, ev), 2);
    EXPECT_EQ(ev[0].kind, Kind::kButtonRelease);
    EXPECT_EQ(ev[1].button, 1);
    EXPECT_EQ(ev[1].time_ns, 9);
    EXPECT_EQ(dec.release_all(10, ev), 0);
    ASSERT_EQ(dec.decode(press, 11, ev, n), ReportStatus::kOk);
    EXPECT_EQ(n, 2);  // pressed again after the reconnect
}

TEST(ReportDescriptor, MalformedDescriptorsNameTheByte) {
    EXPECT_EQ(parse_error({0x05}), "HID report descriptor, byte 0: item runs past the end");
    EXPECT_EQ(parse_error({0xC0}),
              "HID report descriptor, byte 0: End Collection without Collection");
    EXPECT_EQ(parse_error({0xA1, 0x01}), "HID report descriptor, byte 2: unclosed collection");
    EXPECT_EQ(parse_error({0xB4}), "HID report descriptor, byte 0: Pop without Push");
    EXPECT_EQ(parse_error({0x85, 0x00}), "HID report descriptor, byte 0: report ID must be 1..255");
    EXPECT_EQ(parse_error({0x05, 0x09, 0x09, 0x01, 0x95, 0x01, 0x81, 0x02}),
              "HID report descriptor, byte 6: Input with report size 0 or > 32");
    EXPECT_EQ(parse_error({0xFE, 0x05, 0x00}),
              "HID report descriptor, byte 0: truncated long item");
    // A keyboard: keys (page 0x07) but no button and no wheel.
    EXPECT_EQ(parse_error({0x05, 0x07, 0x19, 0xE0, 0x29, 0xE7, 0x75, 0x01, 0x95, 0x08, 0x81, 0x02}),
              "HID report descriptor, byte 12: no button (page 0x09) and no wheel (page 0x01 usage "
              "0x38) input field");
    // 65 bytes of input: longer than any report the handle accepts.
    EXPECT_EQ(parse_error({0x05, 0x09, 0x09, 0x01, 0x75, 0x08, 0x95, 0x41, 0x81, 0x02}),
              "HID report descriptor, byte 8: input report longer than 64 bytes");
}

TEST(ReportDescriptor, PushPopRestoresGlobals) {
    // Push, change the page to Generic Desktop, Pop: the button page comes back.
    const std::vector<std::uint8_t> d = {0x05, 0x09, 0xA4, 0x05, 0x01, 0xB4, 0x09, 0x01, 0x75,
                                         0x01, 0x95, 0x01, 0x81, 0x02, 0x75, 0x07, 0x81, 0x03};
    const HandleLayout l = parse_ok(d);
    EXPECT_TRUE(l.buttons[0].present);
    EXPECT_EQ(l.input_bytes[0], 1);
}

}  // namespace
}  // namespace endotower::hid
