// Binary tool masks and ground-truth homographies from ../shared/data.
#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <sstream>

#include "endotower/eval/annotations.hpp"

namespace endotower::eval {

bool read_tool_mask(const std::string& path, ToolMask& out, std::string& error, int min_area) {
    if (!std::filesystem::is_regular_file(path)) {
        error = "cannot read mask: " + path;
        return false;
    }
    cv::Mat img = cv::imread(path, cv::IMREAD_GRAYSCALE);
    if (img.empty()) {
        error = path + ": not an image OpenCV can decode (expected a PNG mask)";
        return false;
    }
    cv::Mat on = img > 0;  // 255 where set
    out = ToolMask{};
    out.width = img.cols;
    out.height = img.rows;
    out.on.resize(static_cast<std::size_t>(img.cols) * img.rows);
    for (int y = 0; y < img.rows; ++y)
        for (int x = 0; x < img.cols; ++x)
            out.on[static_cast<std::size_t>(y) * img.cols + x] = on.at<std::uint8_t>(y, x) ? 1 : 0;
    cv::Mat labels, stats, centroids;
    const int n = cv::connectedComponentsWithStats(on, labels, stats, centroids, 8, CV_32S);
    for (int i = 1; i < n; ++i) {
        const int area = stats.at<int>(i, cv::CC_STAT_AREA);
        if (area < min_area) continue;
        MaskComponent c;
        c.area = area;
        c.x0 = stats.at<int>(i, cv::CC_STAT_LEFT);
        c.y0 = stats.at<int>(i, cv::CC_STAT_TOP);
        c.x1 = c.x0 + stats.at<int>(i, cv::CC_STAT_WIDTH) - 1;
        c.y1 = c.y0 + stats.at<int>(i, cv::CC_STAT_HEIGHT) - 1;
        c.centroid = {centroids.at<double>(i, 0), centroids.at<double>(i, 1)};
        // Principal axis from the second central moments of the component.
        const cv::Moments m = cv::moments(labels == i, true);
        const double angle = 0.5 * std::atan2(2 * m.mu11, m.mu20 - m.mu02) * 180.0 / M_PI;
        c.axis_deg = angle < 0 ? angle + 180.0 : angle;
        out.components.push_back(c);
    }
    std::sort(out.components.begin(), out.components.end(),
              [](const MaskComponent& a, const MaskComponent& b) { return a.area > b.area; });
    if (out.components.empty()) {
        error = path + ": the mask has no instrument (no component of >= " +
                std::to_string(min_area) + " px)";
        return false;
    }
    return true;
}

namespace {

bool read_filestorage(const std::string& path, Homography& h, std::string& error) {
    try {
        cv::FileStorage fs(path, cv::FileStorage::READ);
        if (!fs.isOpened()) {
            error = path + ": not an OpenCV FileStorage file";
            return false;
        }
        for (cv::FileNodeIterator it = fs.root().begin(); it != fs.root().end(); ++it) {
            cv::Mat m;
            (*it) >> m;
            if (m.empty()) continue;
            if (m.rows != 3 || m.cols != 3 || m.channels() != 1) {
                error = path + ": field '" + (*it).name() + "' must be a 3x3 matrix";
                return false;
            }
            m.convertTo(m, CV_64F);
            for (int i = 0; i < 9; ++i) h[i] = m.at<double>(i / 3, i % 3);
            return true;
        }
        error = path + ": no matrix in the file";
        return false;
    } catch (const cv::Exception& e) {
        error = path + ": cannot parse as OpenCV FileStorage (" + e.msg + ")";
        return false;
    }
}

bool read_text(const std::string& path, Homography& h, std::string& error) {
    std::ifstream in(path);
    if (!in) {
        error = "cannot read homography: " + path;
        return false;
    }
    std::string line, word;
    int n = 0, number = 0;
    while (std::getline(in, line)) {
        ++number;
        std::istringstream words(line);
        while (words >> word) {
            char* end = nullptr;
            const double v = std::strtod(word.c_str(), &end);
            if (end == word.c_str() || *end != 0 || !std::isfinite(v)) {
                error = path + ":" + std::to_string(number) + ": '" + word + "' is not a number";
                return false;
            }
            if (n == 9) {
                error = path + ":" + std::to_string(number) + ": more than 9 numbers (a 3x3 homography)";
                return false;
            }
            h[n++] = v;
        }
    }
    if (n != 9) {
        error = path + ":" + std::to_string(number) + ": " + std::to_string(n) +
                " numbers, a 3x3 homography needs 9";
        return false;
    }
    return true;
}

}  // namespace

bool read_homography(const std::string& path, Homography& out, std::string& error) {
    const std::string ext = std::filesystem::path(path).extension().string();
    if (!std::filesystem::is_regular_file(path)) {
        error = "cannot read homography: " + path;
        return false;
    }
    const bool ok = (ext == ".xml" || ext == ".yml" || ext == ".yaml") ? read_filestorage(path, out, error)
                                                                       : read_text(path, out, error);
    if (!ok) return false;
    Homography inv;
    if (!invert_homography(out, inv)) {
        error = path + ": the homography is singular";
        return false;
    }
    return true;
}

Point2 apply_homography(const Homography& h, Point2 p) {
    const double w = h[6] * p.x + h[7] * p.y + h[8];
    return {(h[0] * p.x + h[1] * p.y + h[2]) / w, (h[3] * p.x + h[4] * p.y + h[5]) / w};
}

bool invert_homography(const Homography& h, Homography& out) {
    const double det = h[0] * (h[4] * h[8] - h[5] * h[7]) - h[1] * (h[3] * h[8] - h[5] * h[6]) +
                       h[2] * (h[3] * h[7] - h[4] * h[6]);
    double scale = 0;
    for (double v : h) scale = std::max(scale, std::abs(v));
    if (!std::isfinite(det) || std::abs(det) <= 1e-12 * scale * scale * scale) return false;
    out = {(h[4] * h[8] - h[5] * h[7]) / det, (h[2] * h[7] - h[1] * h[8]) / det,
           (h[1] * h[5] - h[2] * h[4]) / det, (h[5] * h[6] - h[3] * h[8]) / det,
           (h[0] * h[8] - h[2] * h[6]) / det, (h[2] * h[3] - h[0] * h[5]) / det,
           (h[3] * h[7] - h[4] * h[6]) / det, (h[1] * h[6] - h[0] * h[7]) / det,
           (h[0] * h[4] - h[1] * h[3]) / det};
    return true;
}

}  // namespace endotower::eval
