// Helpers for the calibration tests: simulator frames as GrayImages, real data paths.
#pragma once

#include <gtest/gtest.h>

#include <filesystem>
#include <string>

#include "endotower/calibration/gray_image.hpp"
#include "endotower/scene/renderer.hpp"
#include "endotower/scene/scenario.hpp"

namespace endotower::calibration::test {

inline scene::Scenario scenario_or_fail(const std::string& text) {
    scene::Scenario s;
    std::string error;
    EXPECT_TRUE(scene::parse_scenario(text, "test.yaml", s, error)) << error;
    return s;
}

// Renders frame `index` as a GrayImage (luma) with its truth.
inline GrayImage render_gray(scene::SceneRenderer& r, int index, scene::FrameTruth& truth) {
    scene::Image img;
    r.render(index, img, truth);
    hal::Frame f;
    f.format = {img.width, img.height, img.width * 3, hal::PixelFormat::kBgr24};
    f.data = img.bgr.data();
    GrayImage g;
    gray_from_frame(f, g);
    g.name = "frame " + std::to_string(index);
    return g;
}

inline std::string shared_data(const std::string& sub) {
    return std::string(ENDOTOWER_SHARED_DATA) + "/" + sub;
}

}  // namespace endotower::calibration::test
