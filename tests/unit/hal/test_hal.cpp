#include <gtest/gtest.h>

#include <vector>

#include "endotower/hal/control_merge.hpp"
#include "endotower/hal/frame.hpp"

namespace endotower::hal {
namespace {

class Queue final : public ControlInput {
public:
    explicit Queue(std::vector<ControlEvent> e) : events_(std::move(e)) {}
    bool poll(ControlEvent& out) override {
        if (i_ == events_.size()) return false;
        out = events_[i_++];
        return true;
    }

private:
    std::vector<ControlEvent> events_;
    std::size_t i_ = 0;
};

ControlEvent at(Nanos t, ControlEvent::Kind k = ControlEvent::Kind::kWheel, std::int16_t d = 1) {
    return {k, 0, d, t};
}

TEST(ControlMerge, InterleavesInputsInTimestampOrder) {
    Queue gpio({at(10, ControlEvent::Kind::kButtonPress), at(30, ControlEvent::Kind::kButtonRelease)});
    Queue hid({at(5), at(20, ControlEvent::Kind::kWheel, -1), at(40)});
    ControlMerge m;
    ASSERT_TRUE(m.attach(&gpio));
    ASSERT_TRUE(m.attach(&hid));
    std::vector<Nanos> times;
    ControlEvent e;
    while (m.poll(e)) times.push_back(e.time_ns);
    EXPECT_EQ(times, (std::vector<Nanos>{5, 10, 20, 30, 40}));
}

TEST(ControlMerge, TiesGoToTheEarlierAttachedInput) {
    Queue a({at(7, ControlEvent::Kind::kButtonPress)});
    Queue b({at(7, ControlEvent::Kind::kWheel)});
    ControlMerge m;
    m.attach(&a);
    m.attach(&b);
    ControlEvent e;
    ASSERT_TRUE(m.poll(e));
    EXPECT_EQ(e.kind, ControlEvent::Kind::kButtonPress);
    ASSERT_TRUE(m.poll(e));
    EXPECT_EQ(e.kind, ControlEvent::Kind::kWheel);
    EXPECT_FALSE(m.poll(e));
}

TEST(ControlMerge, RefusesNullAndTooManyInputs) {
    ControlMerge m;
    EXPECT_FALSE(m.attach(nullptr));
    Queue q({});
    for (std::size_t i = 0; i < ControlMerge::kMaxInputs; ++i) EXPECT_TRUE(m.attach(&q));
    EXPECT_FALSE(m.attach(&q));
    EXPECT_EQ(m.size(), ControlMerge::kMaxInputs);
}

TEST(FrameFormat, SizesAndValidity) {
    EXPECT_EQ((FrameFormat{1920, 1080, 5760, PixelFormat::kBgr24}.size_bytes()), 6'220'800u);
    EXPECT_EQ((FrameFormat{1920, 1080, 1920, PixelFormat::kNv12}.size_bytes()), 3'110'400u);
    EXPECT_EQ((FrameFormat{1920, 1080, 3840, PixelFormat::kYuyv}.size_bytes()), 4'147'200u);
    EXPECT_TRUE((FrameFormat{640, 480, 1920, PixelFormat::kBgr24}.valid()));
    EXPECT_FALSE((FrameFormat{640, 480, 1000, PixelFormat::kBgr24}.valid()));  // stride too small
    EXPECT_FALSE((FrameFormat{641, 480, 1282, PixelFormat::kYuyv}.valid()));   // odd width 4:2:2
    EXPECT_FALSE((FrameFormat{0, 480, 0, PixelFormat::kGray8}.valid()));
}

TEST(PixelFormat, NamesRoundTrip) {
    for (PixelFormat f : {PixelFormat::kBgr24, PixelFormat::kRgb24, PixelFormat::kBgra32, PixelFormat::kGray8,
                          PixelFormat::kYuyv, PixelFormat::kUyvy, PixelFormat::kNv12}) {
        PixelFormat back{};
        ASSERT_TRUE(parse_pixel_format(to_string(f), back)) << to_string(f);
        EXPECT_EQ(back, f);
    }
    PixelFormat x{};
    EXPECT_FALSE(parse_pixel_format("mjpeg2", x));
}

}  // namespace
}  // namespace endotower::hal
