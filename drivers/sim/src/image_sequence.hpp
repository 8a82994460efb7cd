// Helpers for recordings stored as numbered images (private to the sim backend):
// listing a directory in frame order, and bringing decoded pictures to BGR24.
#pragma once

#include <algorithm>
#include <cctype>
#include <charconv>
#include <cstdint>
#include <filesystem>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>
#include <string>
#include <system_error>
#include <vector>

namespace endotower::sim::detail {

inline bool is_image_name(const std::filesystem::path& p) {
    std::string ext = p.extension().string();
    for (char& c : ext) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
    return ext == ".png" || ext == ".jpg" || ext == ".jpeg" || ext == ".bmp" || ext == ".tif" ||
           ext == ".tiff";
}

// The image files of `dir` in frame order: by the last number in the stem
// ("frame_2" before "frame_10"), then names without a number in name order. Hidden
// files are left out (they include the FileSink's ".NNNNNN.tmp.png" temporaries).
inline std::vector<std::string> list_image_sequence(const std::string& dir, std::error_code& ec) {
    struct Entry {
        bool numbered = false;
        std::uint64_t number = 0;
        std::string name, path;
    };
    std::vector<Entry> entries;
    for (std::filesystem::directory_iterator it(dir, ec), end; !ec && it != end; it.increment(ec)) {
        const std::filesystem::path& p = it->path();
        std::error_code type_ec;
        Entry e;
        e.name = p.filename().string();
        if (e.name.starts_with('.') || !is_image_name(p) || !it->is_regular_file(type_ec)) continue;
        e.path = p.string();
        const std::string stem = p.stem().string();
        std::size_t end_digit = stem.size();
        while (end_digit > 0 && !std::isdigit(static_cast<unsigned char>(stem[end_digit - 1])))
            --end_digit;
        std::size_t begin = end_digit;
        while (begin > 0 && std::isdigit(static_cast<unsigned char>(stem[begin - 1]))) --begin;
        if (begin < end_digit) {
            const auto r = std::from_chars(stem.data() + begin, stem.data() + end_digit, e.number);
            e.numbered = r.ec == std::errc();  // an overlong number falls back to the name
        }
        entries.push_back(std::move(e));
    }
    std::sort(entries.begin(), entries.end(), [](const Entry& a, const Entry& b) {
        if (a.numbered != b.numbered) return a.numbered;
        if (a.numbered && a.number != b.number) return a.number < b.number;
        return a.name < b.name;
    });
    std::vector<std::string> paths;
    paths.reserve(entries.size());
    for (Entry& e : entries) paths.push_back(std::move(e.path));
    return paths;
}

// Brings a decoded picture to 8-bit, 3-channel BGR: `result` points at `in` when it
// already is, else at `scratch`, which holds the converted pixels. False for layouts
// without a sensible BGR reading.
inline bool to_bgr24(const cv::Mat& in, cv::Mat& scratch, const cv::Mat*& result) {
    if (in.empty()) return false;
    if (in.type() == CV_8UC3) {
        result = &in;
        return true;
    }
    const int cn = in.channels();
    if (cn != 1 && cn != 3 && cn != 4) return false;
    const cv::Mat* src = &in;
    cv::Mat depth8;
    if (in.depth() != CV_8U) {
        // 16-bit spans 0..65535, float pictures 0..1.
        const double scale = in.depth() == CV_16U   ? 1.0 / 257.0
                             : in.depth() >= CV_32F ? 255.0
                                                    : 1.0;
        in.convertTo(depth8, CV_8U, scale);
        src = &depth8;
    }
    if (cn == 1)
        cv::cvtColor(*src, scratch, cv::COLOR_GRAY2BGR);
    else if (cn == 4)
        cv::cvtColor(*src, scratch, cv::COLOR_BGRA2BGR);
    else
        src->copyTo(scratch);
    result = &scratch;
    return true;
}

}  // namespace endotower::sim::detail
