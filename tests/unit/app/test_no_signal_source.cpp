// NoSignalSource: real frames pass through untouched; after the configured silence a
// "NO SIGNAL" card in the source's own format is lent instead, until frames return.
#include <gtest/gtest.h>

#include <deque>
#include <string>

#include "endotower/app/no_signal_source.hpp"
#include "fakes.hpp"

namespace endotower::app {
namespace {

// A YUYV (or BGRA) source that plays a script: 'f' a frame, 't' a timeout (the clock
// moves on by the timeout, as a blocked wait would).
class ScriptSource final : public hal::FrameSource {
public:
    ScriptSource(test::ManualClock& clock, std::string script, hal::PixelFormat pf)
        : clock_(clock), script_(std::move(script)) {
        format_ = {64, 48, 64 * hal::bytes_per_pixel(pf), pf};
        buf_.assign(format_.size_bytes(), 0x55);
    }
    bool start() override { return true; }
    void stop() override {}
    hal::SourceStatus next(hal::Frame& out, hal::Nanos timeout) override {
        if (pos_ == script_.size()) return hal::SourceStatus::kEndOfStream;
        if (script_[pos_++] == 't') {
            clock_.sleep_until(clock_.now() + timeout);
            return hal::SourceStatus::kTimeout;
        }
        out = hal::Frame{};
        out.format = format_;
        out.data = buf_.data();
        out.capture_ns = clock_.now();
        out.sequence = ++seq_;
        out.buffer_index = 2;
        return hal::SourceStatus::kFrame;
    }
    void release(const hal::Frame&) override { ++released; }
    hal::FrameFormat format() const override { return format_; }
    hal::Nanos frame_period() const override { return 16 * hal::kMillisecond; }
    int buffer_count() const override { return 4; }
    const std::string& error() const override { return error_; }
    int released = 0;

private:
    test::ManualClock& clock_;
    std::string script_;
    std::size_t pos_ = 0;
    std::uint64_t seq_ = 0;
    hal::FrameFormat format_;
    std::vector<std::uint8_t> buf_;
    std::string error_;
};

struct CountingLog final : Log {
    std::vector<std::string> lines;
    void write(LogLevel, std::string_view m) override { lines.emplace_back(m); }
};

constexpr hal::Nanos kTimeout = 100 * hal::kMillisecond;

TEST(NoSignalSource, CardAfterTheSilenceThenFramesAgain) {
    test::ManualClock clock;
    ScriptSource inner(clock, "fftttfft", hal::PixelFormat::kYuyv);
    CountingLog log;
    NoSignalSource src(inner, clock, log, 250 * hal::kMillisecond);
    ASSERT_TRUE(src.start());
    hal::Frame f;
    std::string seen;
    std::vector<hal::Frame> frames;
    for (;;) {
        const hal::SourceStatus st = src.next(f, kTimeout);
        if (st == hal::SourceStatus::kEndOfStream) break;
        if (st == hal::SourceStatus::kTimeout) seen += 't';
        if (st == hal::SourceStatus::kFrame) {
            seen += f.buffer_index == NoSignalSource::kCardIndex ? 'C' : 'f';
            frames.push_back(f);
            src.release(f);
        }
    }
    // 100 and 200 ms of silence: still waiting; 300 ms: the card. One timeout after
    // two frames is too short for it.
    EXPECT_EQ(seen, "ffttCfft");
    EXPECT_EQ(inner.released, 4);  // the card never goes back to the camera
    const hal::Frame& card = frames[2];
    EXPECT_EQ(card.format, inner.format());
    EXPECT_EQ(card.sequence, 2u);  // the last real one: no false drops counted
    EXPECT_EQ(card.dmabuf_fd, -1);
    EXPECT_EQ(frames[3].data, frames[0].data);  // real frames untouched
    ASSERT_EQ(log.lines.size(), 2u);
    EXPECT_NE(log.lines[0].find("no signal"), std::string::npos);
    EXPECT_NE(log.lines[1].find("back"), std::string::npos);
}

TEST(NoSignalSource, CardIsBlackWithWhiteWordsInTheMiddle) {
    for (hal::PixelFormat pf : {hal::PixelFormat::kYuyv, hal::PixelFormat::kUyvy,
                                hal::PixelFormat::kBgra32, hal::PixelFormat::kNv12}) {
        test::ManualClock clock;
        ScriptSource inner(clock, "", pf);
        CountingLog log;
        NoSignalSource src(inner, clock, log);
        hal::FrameFormat fmt{640, 360, 0, pf};
        fmt.stride = 640 * hal::bytes_per_pixel(pf);
        src.render(fmt);
        const auto& c = src.card();
        ASSERT_EQ(c.size(), fmt.size_bytes());
        auto luma = [&](int x, int y) -> int {
            const std::uint8_t* row = c.data() + static_cast<std::size_t>(y) * fmt.stride;
            switch (pf) {
                case hal::PixelFormat::kYuyv:
                    return row[2 * x];
                case hal::PixelFormat::kUyvy:
                    return row[2 * x + 1];
                case hal::PixelFormat::kBgra32:
                    return row[4 * x + 1];
                default:
                    return row[x];
            }
        };
        const int black = pf == hal::PixelFormat::kBgra32 ? 0 : 16;  // limited-range YUV black
        EXPECT_EQ(luma(0, 0), black) << hal::to_string(pf);
        EXPECT_EQ(luma(639, 359), black) << hal::to_string(pf);
        int bright = 0, outside = 0;
        for (int y = 0; y < 360; ++y)
            for (int x = 0; x < 640; ++x) {
                const bool lit = luma(x, y) > 200;
                if (y > 120 && y < 240)
                    bright += lit;
                else
                    outside += lit;
            }
        EXPECT_GT(bright, 1000) << hal::to_string(pf);  // the words, in the middle band
        EXPECT_EQ(outside, 0) << hal::to_string(pf);
        if (pf == hal::PixelFormat::kYuyv) {
            EXPECT_EQ(c[1], 128);  // neutral chroma
        } else if (pf == hal::PixelFormat::kNv12) {
            EXPECT_EQ(c[c.size() - 1], 128);
        } else if (pf == hal::PixelFormat::kBgra32) {
            EXPECT_EQ(c[3], 255);
        }
    }
}

}  // namespace
}  // namespace endotower::app
