// Helpers for the scene simulator tests: render a scenario given as text.
#pragma once

#include <gtest/gtest.h>

#include <opencv2/core.hpp>
#include <string>

#include "endotower/scene/renderer.hpp"
#include "endotower/scene/scenario.hpp"

namespace endotower::scene::test {

inline Scenario parse_or_fail(const std::string& text) {
    Scenario s;
    std::string error;
    EXPECT_TRUE(parse_scenario(text, "test.yaml", s, error)) << error;
    return s;
}

struct Rendered {
    cv::Mat image;
    FrameTruth truth;
};

inline Rendered render_frame(SceneRenderer& r, int index) {
    Rendered out;
    Image img;
    r.render(index, img, out.truth);
    out.image = cv::Mat(img.height, img.width, CV_8UC3, img.bgr.data()).clone();
    return out;
}

}  // namespace endotower::scene::test
