// ToolLikelihood::add_files: training images from disk (OpenCV decodes them).
#include <filesystem>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>

#include "endotower/vision/tool_likelihood.hpp"

namespace endotower::vision {

bool ToolLikelihood::add_files(const std::string& image, const std::string& labels, double weight,
                               std::string& error, int augment, double gain_spread, std::uint64_t seed) {
    for (const std::string* p : {&image, &labels})
        if (!std::filesystem::is_regular_file(*p)) {
            error = "cannot read " + *p;
            return false;
        }
    cv::Mat img, lab;
    try {
        img = cv::imread(image, cv::IMREAD_COLOR);
        lab = cv::imread(labels, cv::IMREAD_GRAYSCALE);
    } catch (const cv::Exception& e) {
        error = image + ": cannot decode (" + e.msg + ")";
        return false;
    }
    if (img.empty()) {
        error = image + ": not an image OpenCV can decode";
        return false;
    }
    if (lab.empty()) {
        error = labels + ": not an image OpenCV can decode";
        return false;
    }
    if (img.size() != lab.size()) {
        error = labels + ": " + std::to_string(lab.cols) + "x" + std::to_string(lab.rows) + " labels for a " +
                std::to_string(img.cols) + "x" + std::to_string(img.rows) + " image (" + image + ")";
        return false;
    }
    if (!lab.isContinuous()) lab = lab.clone();
    hal::Frame f;
    f.format = {img.cols, img.rows, static_cast<int>(img.step), hal::PixelFormat::kBgr24};
    f.data = img.data;
    add(f, lab.data, weight);
    cv::RNG rng(seed);
    for (int k = 0; k < augment; ++k) {
        const std::array<double, 3> gains = {rng.uniform(1 - gain_spread, 1 + gain_spread),
                                             rng.uniform(1 - gain_spread, 1 + gain_spread),
                                             rng.uniform(1 - gain_spread, 1 + gain_spread)};
        add(f, lab.data, weight, gains);
    }
    return true;
}

}  // namespace endotower::vision
