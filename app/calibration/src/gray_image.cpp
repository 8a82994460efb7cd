#include "endotower/calibration/gray_image.hpp"

#include <algorithm>
#include <cctype>
#include <filesystem>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <system_error>

namespace endotower::calibration {

namespace fs = std::filesystem;

bool load_gray_image(const std::string& path, GrayImage& out, std::string& error) {
    const cv::Mat m = cv::imread(path, cv::IMREAD_GRAYSCALE);
    if (m.empty()) {
        error = path + ": cannot read the image (missing or not an image file)";
        return false;
    }
    out.width = m.cols;
    out.height = m.rows;
    out.pixels.assign(m.datastart, m.dataend);
    out.name = fs::path(path).filename().string();
    return true;
}

bool gray_from_frame(const hal::Frame& frame, GrayImage& out) {
    const hal::FrameFormat& f = frame.format;
    if (!f.valid() || frame.data == nullptr) return false;
    cv::Mat gray;
    switch (f.pixel_format) {
        case hal::PixelFormat::kBgr24:
            cv::cvtColor(cv::Mat(f.height, f.width, CV_8UC3, frame.data, f.stride), gray,
                         cv::COLOR_BGR2GRAY);
            break;
        case hal::PixelFormat::kRgb24:
            cv::cvtColor(cv::Mat(f.height, f.width, CV_8UC3, frame.data, f.stride), gray,
                         cv::COLOR_RGB2GRAY);
            break;
        case hal::PixelFormat::kBgra32:
            cv::cvtColor(cv::Mat(f.height, f.width, CV_8UC4, frame.data, f.stride), gray,
                         cv::COLOR_BGRA2GRAY);
            break;
        case hal::PixelFormat::kYuyv:
            cv::cvtColor(cv::Mat(f.height, f.width, CV_8UC2, frame.data, f.stride), gray,
                         cv::COLOR_YUV2GRAY_YUYV);
            break;
        case hal::PixelFormat::kUyvy:
            cv::cvtColor(cv::Mat(f.height, f.width, CV_8UC2, frame.data, f.stride), gray,
                         cv::COLOR_YUV2GRAY_UYVY);
            break;
        case hal::PixelFormat::kGray8:
        case hal::PixelFormat::kNv12:  // the Y plane comes first
            gray = cv::Mat(f.height, f.width, CV_8UC1, frame.data, f.stride).clone();
            break;
    }
    out.width = gray.cols;
    out.height = gray.rows;
    out.pixels.assign(gray.datastart, gray.dataend);
    return true;
}

bool list_images(const std::string& dir, std::vector<std::string>& paths, std::string& error) {
    std::error_code ec;
    fs::directory_iterator it(dir, ec);
    if (ec) {
        error = dir + ": cannot read the folder (" + ec.message() + ")";
        return false;
    }
    paths.clear();
    for (const fs::directory_entry& e : it) {
        if (!e.is_regular_file(ec)) continue;
        std::string ext = e.path().extension().string();
        std::transform(ext.begin(), ext.end(), ext.begin(),
                       [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
        if (ext == ".png" || ext == ".jpg" || ext == ".jpeg" || ext == ".bmp" || ext == ".tif" ||
            ext == ".tiff")
            paths.push_back(e.path().string());
    }
    std::sort(paths.begin(), paths.end());
    if (paths.empty()) {
        error = dir + ": no images (png, jpg, bmp, tif) in the folder";
        return false;
    }
    return true;
}

}  // namespace endotower::calibration
