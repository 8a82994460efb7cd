// MjpegDecoder on JPEGs made here from a generated picture: OpenCV's cv::imencode
// (4:2:0, standard Huffman tables, baseline or progressive) and libjpeg directly (4:2:2
// as UVC cameras send, separate scans per component). Ground truth: the original
// picture (error bound per quality) and cv::imdecode of the same bytes (the same
// libjpeg-turbo with the same settings: identical pixels).
#include <gtest/gtest.h>

// clang-format off
#include <cstdio>
#include <jpeglib.h>
// clang-format on

#include <cstdlib>
#include <cstring>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <random>
#include <string>
#include <vector>

#include "endotower/v4l2/mjpeg_decoder.hpp"
#include "heap_counter.hpp"

namespace endotower::v4l2 {
namespace {

using Bytes = std::vector<std::uint8_t>;

// Smooth gradients with sharp-edged shapes: what an endoscope picture has (tissue and
// instrument edges). Width and height need not be multiples of the MCU.
cv::Mat picture(int width, int height) {
    cv::Mat m(height, width, CV_8UC3);
    for (int y = 0; y < height; ++y)
        for (int x = 0; x < width; ++x)
            m.at<cv::Vec3b>(y, x) = {
                static_cast<std::uint8_t>(40 + 150 * x / width),
                static_cast<std::uint8_t>(60 + 120 * y / height),
                static_cast<std::uint8_t>(200 - 100 * (x + y) / (width + height))};
    for (int y = height / 4; y < height / 2; ++y)  // a bright instrument-like bar
        for (int x = width / 5; x < width / 5 + width / 3; ++x)
            m.at<cv::Vec3b>(y, x) = {230, 230, 235};
    for (int y = 0; y < height; ++y)  // a dark disc
        for (int x = 0; x < width; ++x) {
            const int dx = x - 3 * width / 4, dy = y - 2 * height / 3;
            if (dx * dx + dy * dy < height * height / 25) m.at<cv::Vec3b>(y, x) = {20, 30, 90};
        }
    return m;
}

Bytes imencode(const cv::Mat& m, int quality, bool progressive = false) {
    Bytes out;
    EXPECT_TRUE(cv::imencode(
        ".jpg", m, out,
        {cv::IMWRITE_JPEG_QUALITY, quality, cv::IMWRITE_JPEG_PROGRESSIVE, progressive ? 1 : 0}));
    return out;
}

// libjpeg's own encoder: luma sampled h x v (2x1 = 4:2:2), chroma 1x1; optionally one
// scan per component (sequential but multi-scan).
Bytes libjpeg_encode(const cv::Mat& m, int quality, int h, int v, bool scan_per_component) {
    jpeg_compress_struct c{};
    jpeg_error_mgr err{};
    c.err = jpeg_std_error(&err);
    jpeg_create_compress(&c);
    unsigned char* buf = nullptr;
    unsigned long size = 0;
    jpeg_mem_dest(&c, &buf, &size);
    c.image_width = static_cast<JDIMENSION>(m.cols);
    c.image_height = static_cast<JDIMENSION>(m.rows);
    c.input_components = 3;
    c.in_color_space = JCS_EXT_BGR;
    jpeg_set_defaults(&c);
    jpeg_set_quality(&c, quality, TRUE);
    c.comp_info[0].h_samp_factor = h;
    c.comp_info[0].v_samp_factor = v;
    jpeg_scan_info scans[3]{};
    if (scan_per_component) {
        for (int i = 0; i < 3; ++i) {
            scans[i].comps_in_scan = 1;
            scans[i].component_index[0] = i;
            scans[i].Ss = 0;
            scans[i].Se = 63;
        }
        c.scan_info = scans;
        c.num_scans = 3;
    }
    jpeg_start_compress(&c, TRUE);
    while (c.next_scanline < c.image_height) {
        JSAMPROW row = const_cast<JSAMPROW>(m.ptr<std::uint8_t>(static_cast<int>(c.next_scanline)));
        jpeg_write_scanlines(&c, &row, 1);
    }
    jpeg_finish_compress(&c);
    Bytes out(buf, buf + size);
    std::free(buf);
    jpeg_destroy_compress(&c);
    return out;
}

// The JPEG without its DHT segments (what many UVC cameras send).
Bytes strip_dht(const Bytes& jpeg) {
    Bytes out(jpeg.begin(), jpeg.begin() + 2);  // SOI
    std::size_t i = 2;
    while (i + 4 <= jpeg.size() && jpeg[i] == 0xff) {
        const std::uint8_t marker = jpeg[i + 1];
        const std::size_t length = (jpeg[i + 2] << 8) | jpeg[i + 3];
        if (marker == 0xda) break;  // SOS: entropy-coded data follows, copy the rest
        if (marker != 0xc4) out.insert(out.end(), jpeg.begin() + i, jpeg.begin() + i + 2 + length);
        i += 2 + length;
    }
    out.insert(out.end(), jpeg.begin() + i, jpeg.end());
    return out;
}

bool has_marker(const Bytes& jpeg, std::uint8_t marker) {
    for (std::size_t i = 0; i + 1 < jpeg.size(); ++i)
        if (jpeg[i] == 0xff && jpeg[i + 1] == marker) return true;
    return false;
}

struct Decoded {
    MjpegResult result;
    cv::Mat image;
};

Decoded decode(MjpegDecoder& d, const Bytes& jpeg, int width, int height,
               std::uint64_t sequence = 1) {
    cv::Mat out(height, width, CV_8UC3, cv::Scalar(1, 2, 3));
    const MjpegResult r = d.decode(jpeg.data(), jpeg.size(), sequence, out.data, width, height,
                                   static_cast<int>(out.step));
    return {r, out};
}

double mean_abs_error(const cv::Mat& a, const cv::Mat& b) {
    cv::Mat diff;
    cv::absdiff(a, b, diff);
    const cv::Scalar s = cv::mean(diff);
    return (s[0] + s[1] + s[2]) / 3.0;
}

// Mean absolute error bounds (levels of 255, mean over B, G, R) on picture(): twice what
// libjpeg-turbo 2.1.5 measures at both sizes (q95 0.53-0.59, q90 0.64-0.68, q75
// 1.05-1.13, q50 1.36-1.53), so an encoder change does not trip them, while a decoder
// with swapped channels, wrong rows or wrong chroma siting is off by tens of levels.
constexpr struct {
    int quality;
    double max_mae;
} kQualityBounds[] = {{95, 1.2}, {90, 1.4}, {75, 2.3}, {50, 3.1}};

TEST(MjpegDecoder, DecodesOpenCvJpegsExactlyAsLibjpegDoes) {
    for (const cv::Size size : {cv::Size(640, 480), cv::Size(651, 357)}) {
        const cv::Mat original = picture(size.width, size.height);
        for (const auto& [quality, max_mae] : kQualityBounds) {
            const Bytes jpeg = imencode(original, quality);
            MjpegDecoder d("/dev/video7");
            const Decoded got = decode(d, jpeg, size.width, size.height);
            ASSERT_EQ(got.result, MjpegResult::kDecoded) << d.message();
            EXPECT_TRUE(d.message().empty());
            EXPECT_EQ(cv::norm(got.image, cv::imdecode(jpeg, cv::IMREAD_COLOR), cv::NORM_INF), 0.0)
                << size << " q" << quality;
            const double mae = mean_abs_error(got.image, original);
            EXPECT_LE(mae, max_mae) << size << " q" << quality;
            cv::Mat swapped;  // the bound tells a decoder with R and B swapped apart
            cv::cvtColor(got.image, swapped, cv::COLOR_BGR2RGB);
            EXPECT_GT(mean_abs_error(swapped, original), 10 * max_mae);
            EXPECT_GT(mae, 0.0);  // it is lossy: the picture was really decoded, not copied
            EXPECT_EQ(d.decoded(), 1u);
            EXPECT_EQ(d.rejected(), 0u);
        }
    }
}

TEST(MjpegDecoder, DecodesUvcStyle422AndStrideWiderThanTheRow) {
    const cv::Mat original = picture(640, 360);
    const Bytes jpeg = libjpeg_encode(original, 90, 2, 1, false);
    MjpegDecoder d("/dev/video0");
    cv::Mat wide(360, 700, CV_8UC3, cv::Scalar(7, 7, 7));  // stride 2100 bytes
    ASSERT_EQ(
        d.decode(jpeg.data(), jpeg.size(), 5, wide.data, 640, 360, static_cast<int>(wide.step)),
        MjpegResult::kDecoded)
        << d.message();
    const cv::Mat got = wide(cv::Rect(0, 0, 640, 360));
    EXPECT_EQ(cv::norm(got, cv::imdecode(jpeg, cv::IMREAD_COLOR), cv::NORM_INF), 0.0);
    EXPECT_LE(mean_abs_error(got, original), 1.4);  // the q90 bound
    // Nothing written past the frame's width.
    const cv::Mat untouched(360, 60, CV_8UC3, cv::Scalar(7, 7, 7));
    EXPECT_EQ(cv::norm(wide(cv::Rect(640, 0, 60, 360)), untouched, cv::NORM_INF), 0.0);
}

TEST(MjpegDecoder, GreyJpegBecomesBgrWithEqualChannels) {
    cv::Mat grey;
    cv::extractChannel(picture(320, 240), grey, 1);
    Bytes jpeg;
    ASSERT_TRUE(cv::imencode(".jpg", grey, jpeg, {cv::IMWRITE_JPEG_QUALITY, 90}));
    MjpegDecoder d("/dev/video0");
    const Decoded got = decode(d, jpeg, 320, 240);
    ASSERT_EQ(got.result, MjpegResult::kDecoded) << d.message();
    const cv::Mat ref = cv::imdecode(jpeg, cv::IMREAD_GRAYSCALE);
    cv::Mat channels[3];
    cv::split(got.image, channels);
    for (const cv::Mat& c : channels) EXPECT_EQ(cv::norm(c, ref, cv::NORM_INF), 0.0);
}

TEST(MjpegDecoder, InsertsTheStandardHuffmanTablesWhenDhtIsMissing) {
    const cv::Mat original = picture(640, 480);
    const Bytes jpeg = imencode(original, 90);  // OpenCV writes the standard tables
    const Bytes bare = strip_dht(jpeg);
    ASSERT_TRUE(has_marker(jpeg, 0xc4));
    ASSERT_FALSE(has_marker(bare, 0xc4));
    ASSERT_LT(bare.size() + 400, jpeg.size());  // four tables: 33 + 183 + 33 + 183 bytes
    MjpegDecoder with("/dev/video0"), without("/dev/video0");
    const Decoded a = decode(with, jpeg, 640, 480);
    const Decoded b = decode(without, bare, 640, 480);
    ASSERT_EQ(a.result, MjpegResult::kDecoded) << with.message();
    ASSERT_EQ(b.result, MjpegResult::kDecoded) << without.message();
    EXPECT_EQ(cv::norm(a.image, b.image, cv::NORM_INF), 0.0);
    // And over several frames of one decoder (tables re-inserted or kept, never lost).
    for (std::uint64_t s = 2; s < 5; ++s) {
        const Decoded again = decode(without, bare, 640, 480, s);
        ASSERT_EQ(again.result, MjpegResult::kDecoded) << without.message();
        EXPECT_EQ(cv::norm(again.image, a.image, cv::NORM_INF), 0.0);
    }
}

TEST(MjpegDecoder, DhtLessFrameAfterCustomTablesUsesTheStandardOnes) {
    // An optimised JPEG carries its own (non-standard) tables; a DHT-less frame after it
    // must not decode with them (libjpeg-turbo 2.1 alone would: "bad Huffman code").
    const cv::Mat original = picture(640, 480);
    Bytes optimised;
    ASSERT_TRUE(cv::imencode(".jpg", original, optimised,
                             {cv::IMWRITE_JPEG_QUALITY, 90, cv::IMWRITE_JPEG_OPTIMIZE, 1}));
    const Bytes standard = imencode(original, 90);
    const Bytes bare = strip_dht(standard);
    const cv::Mat reference = cv::imdecode(standard, cv::IMREAD_COLOR);
    MjpegDecoder d("/dev/video0");
    for (int round = 0; round < 2; ++round) {
        const Decoded a = decode(d, optimised, 640, 480);
        ASSERT_EQ(a.result, MjpegResult::kDecoded) << d.message();
        EXPECT_EQ(cv::norm(a.image, cv::imdecode(optimised, cv::IMREAD_COLOR), cv::NORM_INF), 0.0);
        const Decoded b = decode(d, bare, 640, 480);
        ASSERT_EQ(b.result, MjpegResult::kDecoded) << d.message();
        EXPECT_EQ(cv::norm(b.image, reference, cv::NORM_INF), 0.0);
    }
}

TEST(MjpegDecoder, RejectsBrokenBuffersCountsThemAndDecodesTheNextGoodOne) {
    const cv::Mat original = picture(640, 480);
    const Bytes good = imencode(original, 90);
    const cv::Mat reference = cv::imdecode(good, cv::IMREAD_COLOR);
    std::mt19937 rng(9);
    Bytes random(good.size());
    for (auto& b : random) b = static_cast<std::uint8_t>(rng());
    Bytes random_after_soi = random;
    random_after_soi[0] = 0xff;
    random_after_soi[1] = 0xd8;
    const struct {
        const char* what;
        Bytes bytes;
        const char* reason;
    } cases[] = {
        {"empty", {}, "empty buffer (0 bytes)"},
        {"truncated in the scan", Bytes(good.begin(), good.begin() + good.size() / 2),
         "corrupt JPEG (Premature end of JPEG file)"},
        {"truncated in the header", Bytes(good.begin(), good.begin() + 300), "corrupt JPEG"},
        {"random", random, "corrupt JPEG (Not a JPEG file"},
        {"random after SOI", random_after_soi, "corrupt JPEG"},
        {"SOI only", Bytes{0xff, 0xd8}, "corrupt JPEG"},
    };
    MjpegDecoder d("/dev/video3");
    std::uint64_t sequence = 100;
    for (const auto& c : cases) {
        const Decoded bad = decode(d, c.bytes, 640, 480, sequence);
        EXPECT_EQ(bad.result, MjpegResult::kCorrupt) << c.what;
        const std::string head =
            "/dev/video3: MJPEG buffer sequence " + std::to_string(sequence) + ": " + c.reason;
        EXPECT_EQ(d.message().rfind(head, 0), 0u) << c.what << ": " << d.message();
        EXPECT_NE(d.message().find("frame dropped"), std::string::npos) << d.message();
        ++sequence;
        const Decoded next = decode(d, good, 640, 480, sequence++);
        ASSERT_EQ(next.result, MjpegResult::kDecoded) << c.what << ": " << d.message();
        EXPECT_EQ(cv::norm(next.image, reference, cv::NORM_INF), 0.0) << c.what;
        EXPECT_TRUE(d.message().empty());
    }
    EXPECT_EQ(d.rejected(), std::size(cases));
    EXPECT_EQ(d.decoded(), std::size(cases));
}

TEST(MjpegDecoder, ToleratesPaddingAfterTheImage) {
    // UVC payloads may carry zeros after EOI; libjpeg stops at EOI.
    Bytes jpeg = imencode(picture(320, 240), 90);
    const cv::Mat reference = cv::imdecode(jpeg, cv::IMREAD_COLOR);
    jpeg.resize(jpeg.size() + 4096, 0);
    MjpegDecoder d("/dev/video0");
    const Decoded got = decode(d, jpeg, 320, 240);
    ASSERT_EQ(got.result, MjpegResult::kDecoded) << d.message();
    EXPECT_EQ(cv::norm(got.image, reference, cv::NORM_INF), 0.0);
}

TEST(MjpegDecoder, RefusesProgressiveMultiScanAndOtherSizes) {
    const cv::Mat original = picture(640, 480);
    const Bytes good = imencode(original, 90);
    const Bytes progressive = imencode(original, 90, true);
    const Bytes multi_scan = libjpeg_encode(original, 90, 2, 2, true);
    ASSERT_TRUE(has_marker(progressive, 0xc2));  // SOF2
    MjpegDecoder d("/dev/video0");
    EXPECT_EQ(decode(d, progressive, 640, 480, 7).result, MjpegResult::kUnsupported);
    EXPECT_EQ(d.message(),
              "/dev/video0: MJPEG buffer sequence 7: progressive JPEG is not supported (cameras "
              "send baseline); frame dropped");
    EXPECT_EQ(decode(d, good, 640, 480).result, MjpegResult::kDecoded) << d.message();
    EXPECT_EQ(decode(d, multi_scan, 640, 480, 8).result, MjpegResult::kUnsupported);
    EXPECT_EQ(d.message(),
              "/dev/video0: MJPEG buffer sequence 8: multi-scan JPEG is not supported (cameras "
              "send baseline); frame dropped");
    EXPECT_EQ(decode(d, good, 640, 480).result, MjpegResult::kDecoded) << d.message();
    EXPECT_EQ(decode(d, good, 1280, 720, 9).result, MjpegResult::kWrongSize);
    EXPECT_EQ(d.message(),
              "/dev/video0: MJPEG buffer sequence 9: the JPEG is 640x480, the format is "
              "1280x720; frame dropped");
    EXPECT_EQ(decode(d, good, 640, 480).result, MjpegResult::kDecoded) << d.message();
    EXPECT_EQ(d.rejected(), 3u);
}

TEST(MjpegDecoder, AllocatesNothingInSteadyStateGoodOrBad) {
    if (test::heap_allocations() < 0) GTEST_SKIP() << "heap counting is off under a sanitizer";
    const cv::Mat original = picture(1280, 720);
    const Bytes good = imencode(original, 90);
    const Bytes uvc = strip_dht(libjpeg_encode(original, 85, 2, 1, false));
    const Bytes truncated(good.begin(), good.begin() + good.size() / 3);
    const Bytes progressive = imencode(original, 90, true);
    Bytes random(5000);
    std::mt19937 rng(3);
    for (auto& b : random) b = static_cast<std::uint8_t>(rng());
    cv::Mat out(720, 1280, CV_8UC3);
    MjpegDecoder d("/dev/video0");
    auto run = [&](const Bytes& b, std::uint64_t s) {
        return d.decode(b.data(), b.size(), s, out.data, 1280, 720, static_cast<int>(out.step));
    };
    // Warm-up: the first frames size the arena (and libjpeg fills its permanent pool).
    for (int i = 0; i < 2; ++i) {
        ASSERT_EQ(run(good, 1), MjpegResult::kDecoded) << d.message();
        ASSERT_EQ(run(uvc, 2), MjpegResult::kDecoded) << d.message();
        run(truncated, 3);
        run(progressive, 4);
        run(random, 5);
    }
    const std::uint64_t growths = d.arena_growths();
    const std::size_t arena = d.arena_bytes();
    EXPECT_GT(arena, 0u);
    test::set_counting(true);
    int decoded = 0;
    for (std::uint64_t s = 10; s < 40; ++s) {
        decoded += run(good, s) == MjpegResult::kDecoded;
        decoded += run(uvc, s) == MjpegResult::kDecoded;
        EXPECT_NE(run(truncated, s), MjpegResult::kDecoded);
        EXPECT_NE(run(progressive, s), MjpegResult::kDecoded);
        EXPECT_NE(run(random, s), MjpegResult::kDecoded);
        EXPECT_NE(run({}, s), MjpegResult::kDecoded);
    }
    test::set_counting(false);
    EXPECT_EQ(test::heap_allocations(), 0);
    EXPECT_EQ(test::c_allocations(), 0);
    EXPECT_EQ(decoded, 60);
    EXPECT_EQ(d.arena_growths(), growths);
    EXPECT_EQ(d.arena_bytes(), arena);
}

TEST(MjpegDecoder, CounterSeesLibjpegsOwnAllocations) {
    // The counter is live: a decoder's first frame allocates (the arena, libjpeg's tables).
    if (test::heap_allocations() < 0) GTEST_SKIP() << "heap counting is off under a sanitizer";
    const Bytes good = imencode(picture(320, 240), 90);
    test::set_counting(true);
    MjpegDecoder d("/dev/video0");
    EXPECT_EQ(decode(d, good, 320, 240).result, MjpegResult::kDecoded);
    test::set_counting(false);
    EXPECT_GT(test::heap_allocations() + test::c_allocations(), 2);
    EXPECT_EQ(d.arena_growths(), 1u);
}

}  // namespace
}  // namespace endotower::v4l2
