#include "endotower/calibration/separation_table.hpp"

#include <algorithm>
#include <cmath>
#include <opencv2/imgproc.hpp>

#include "blob_centroid.hpp"

namespace endotower::calibration {

bool SeparationTable::validate(std::string& error) const {
    if (distances_mm.size() != separation_px.size()) {
        error = "separation table: " + std::to_string(distances_mm.size()) + " distances but " +
                std::to_string(separation_px.size()) + " separations";
        return false;
    }
    if (distances_mm.size() < 2) {
        error = "separation table: needs at least two distances";
        return false;
    }
    if (!(marker_mm > 0)) {
        error = "separation table: marker separation must be positive";
        return false;
    }
    for (std::size_t i = 0; i < distances_mm.size(); ++i) {
        if (!(distances_mm[i] > 0) || !(separation_px[i] > 0)) {
            error = "separation table: row " + std::to_string(i + 1) + " is not positive";
            return false;
        }
        if (i > 0 && !(distances_mm[i] > distances_mm[i - 1])) {
            error = "separation table: distances must increase (row " + std::to_string(i + 1) + ")";
            return false;
        }
        if (i > 0 && !(separation_px[i] < separation_px[i - 1])) {
            error = "separation table: separation must fall with distance (row " +
                    std::to_string(i + 1) + ": " + std::to_string(separation_px[i]) + " px at " +
                    std::to_string(distances_mm[i]) + " mm)";
            return false;
        }
    }
    return true;
}

double SeparationTable::separation_at(double z) const {
    const std::size_t n = distances_mm.size();
    std::size_t i = 1;
    while (i + 1 < n && distances_mm[i] < z) ++i;
    const double z0 = distances_mm[i - 1], z1 = distances_mm[i];
    const double s0 = separation_px[i - 1], s1 = separation_px[i];
    return s0 + (s1 - s0) * ((z - z0) / (z1 - z0));
}

double SeparationTable::depth_for_separation(double s) const {
    const std::size_t n = separation_px.size();
    std::size_t i = 1;
    while (i + 1 < n && separation_px[i] > s) ++i;
    const double z0 = distances_mm[i - 1], z1 = distances_mm[i];
    const double s0 = separation_px[i - 1], s1 = separation_px[i];
    return z0 + (z1 - z0) * ((s - s0) / (s1 - s0));
}

bool detect_two_dots(const GrayImage& image, const FovCircle& fov, Point2& a, Point2& b,
                     std::string& error) {
    const std::string where = image.name.empty() ? std::string("image") : image.name;
    const cv::Mat gray(image.height, image.width, CV_8UC1,
                       const_cast<std::uint8_t*>(image.pixels.data()));
    cv::Mat inside = cv::Mat::zeros(gray.size(), CV_8UC1);
    cv::circle(inside, cv::Point(cvRound(fov.cx), cvRound(fov.cy)), cvRound(fov.radius * 0.97), 255,
               cv::FILLED);
    const double level = cv::mean(gray, inside)[0];
    cv::Mat dark;
    cv::threshold(gray, dark, 0.5 * level, 255, cv::THRESH_BINARY_INV);
    dark &= inside;
    cv::Mat labels, stats, cents;
    const int n = cv::connectedComponentsWithStats(dark, labels, stats, cents, 8, CV_32S);
    std::vector<std::pair<int, int>> blobs;  // (area, label)
    for (int i = 1; i < n; ++i) {
        const int area = stats.at<int>(i, cv::CC_STAT_AREA);
        const int w = stats.at<int>(i, cv::CC_STAT_WIDTH), h = stats.at<int>(i, cv::CC_STAT_HEIGHT);
        // A dot is compact: it fills a good part of its box and is not a thin stripe.
        if (area < 4 || area < 0.5 * w * h || std::max(w, h) > 2.5 * std::min(w, h)) continue;
        blobs.push_back({area, i});
    }
    if (blobs.size() < 2) {
        error = where + ": two-dot marker not found (" + std::to_string(blobs.size()) +
                " dark dot(s) inside the field of view)";
        return false;
    }
    std::sort(blobs.rbegin(), blobs.rend());
    if (blobs[1].first < 0.5 * blobs[0].first) {
        error = where + ": two-dot marker not found (the two largest dark blobs differ in size: " +
                std::to_string(blobs[0].first) + " and " + std::to_string(blobs[1].first) + " px)";
        return false;
    }
    a = {cents.at<double>(blobs[0].second, 0), cents.at<double>(blobs[0].second, 1)};
    b = {cents.at<double>(blobs[1].second, 0), cents.at<double>(blobs[1].second, 1)};
    refine_dark_centroid(gray, labels, stats, blobs[0].second, a);
    refine_dark_centroid(gray, labels, stats, blobs[1].second, b);
    return true;
}

}  // namespace endotower::calibration
