// Procedural tissue texture on the tissue plane (private): albedo (linear BGR), a
// wetness map that scales the specular glints, and the slope of a height field that
// tilts the surface normal (so glints sit where the wet bumps face the light).
// Coordinates are millimetres on the plane; outside the generated patch the texture
// repeats mirrored, so a moving endoscope never runs off it.
#pragma once

#include <cmath>
#include <cstdint>
#include <opencv2/core.hpp>
#include <string>

#include "endotower/scene/scenario.hpp"

namespace endotower::scene::detail {

struct TexSample {
    float b, g, r, wet, gu, gv;
};

class TissueTexture {
public:
    // Covers [u0, u0 + width*texel) x [v0, v0 + height*texel) mm. False with `error`
    // if spec.image cannot be read.
    bool generate(const TissueSpec& spec, double u0, double v0, double texel_mm, int width,
                  int height, std::uint64_t seed, std::string& error);
    bool empty() const { return tex_.empty(); }

    TexSample sample(double u, double v) const {
        double x = mirror((u - u0_) / texel_ - 0.5, tex_.cols);
        double y = mirror((v - v0_) / texel_ - 0.5, tex_.rows);
        const int x0 = static_cast<int>(x), y0 = static_cast<int>(y);
        const int x1 = std::min(x0 + 1, tex_.cols - 1), y1 = std::min(y0 + 1, tex_.rows - 1);
        const float fx = static_cast<float>(x - x0), fy = static_cast<float>(y - y0);
        const float* a = tex_.ptr<float>(y0) + 6 * x0;
        const float* b = tex_.ptr<float>(y0) + 6 * x1;
        const float* c = tex_.ptr<float>(y1) + 6 * x0;
        const float* d = tex_.ptr<float>(y1) + 6 * x1;
        float o[6];
        for (int i = 0; i < 6; ++i) {
            const float top = a[i] + fx * (b[i] - a[i]), bot = c[i] + fx * (d[i] - c[i]);
            o[i] = top + fy * (bot - top);
        }
        return {o[0], o[1], o[2], o[3], o[4], o[5]};
    }

private:
    static double mirror(double x, int n) {
        const double period = 2.0 * (n - 1);
        if (period <= 0) return 0;
        x = std::fmod(x, period);
        if (x < 0) x += period;
        if (x > n - 1) x = period - x;
        return std::clamp(x, 0.0, static_cast<double>(n - 1) - 1e-6);
    }
    cv::Mat tex_;  // CV_32FC(6): b, g, r, wet, dh/du, dh/dv
    double u0_ = 0, v0_ = 0, texel_ = 1;
};

}  // namespace endotower::scene::detail
