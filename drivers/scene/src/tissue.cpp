#include "tissue.hpp"

#include <algorithm>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <vector>

#include "rng.hpp"

namespace endotower::scene::detail {

namespace {

float srgb_to_linear(float c) {
    return c <= 0.04045f ? c / 12.92f : std::pow((c + 0.055f) / 1.055f, 2.4f);
}

// Smooth noise in about [-1, 1] with features of `cell_mm`: a coarse grid of random
// values, upsampled bicubically (deterministic, and fast for large textures).
cv::Mat octave(Rng& rng, int w, int h, double texel, double cell_mm) {
    const int gw = std::max(2, static_cast<int>(std::ceil(w * texel / cell_mm)) + 1);
    const int gh = std::max(2, static_cast<int>(std::ceil(h * texel / cell_mm)) + 1);
    cv::Mat grid(gh, gw, CV_32F);
    for (int y = 0; y < gh; ++y)
        for (int x = 0; x < gw; ++x)
            grid.at<float>(y, x) = static_cast<float>(rng.uniform(-1.0, 1.0));
    cv::Mat out;
    cv::resize(grid, out, cv::Size(w, h), 0, 0, cv::INTER_CUBIC);
    return out;
}

float smoothstep(float a, float b, float x) {
    const float t = std::clamp((x - a) / (b - a), 0.0f, 1.0f);
    return t * t * (3 - 2 * t);
}

// Branching random walks: vessels under the serosa.
void draw_vessels(Rng& rng, cv::Mat& mask, double texel, double amount) {
    const double area = mask.cols * texel * mask.rows * texel;
    const int count = static_cast<int>(amount * area / 500.0);
    for (int v = 0; v < count; ++v) {
        // One draw per statement: the order of a call's arguments is unspecified (GCC
        // evaluates them right to left on x86-64, left to right on arm64), and the
        // texture must not depend on the target. y first keeps the x86 textures.
        const double py = rng.uniform(0, mask.rows);
        cv::Point2d p(rng.uniform(0, mask.cols), py);
        double dir = rng.uniform(0, 2 * M_PI);
        double width_mm = rng.uniform(0.25, 1.1);
        const int steps = static_cast<int>(rng.uniform(30, 110));
        std::vector<cv::Point> pts{cv::Point(cvRound(p.x * 4), cvRound(p.y * 4))};
        for (int s = 0; s < steps; ++s) {
            dir += rng.uniform(-0.35, 0.35);
            p += cv::Point2d(std::cos(dir), std::sin(dir)) * (0.9 / texel);
            pts.emplace_back(cvRound(p.x * 4), cvRound(p.y * 4));
            if (s % 25 == 24) {  // a thinner branch, drawn now, then carry on
                const int th = std::max(1, cvRound(width_mm * 0.6 / texel));
                cv::polylines(mask, pts, false, cv::Scalar(1.0), th, cv::LINE_AA, 2);
                pts = {pts.back()};
                width_mm *= 0.8;
                dir += rng.uniform(-0.9, 0.9);
            }
        }
        const int th = std::max(1, cvRound(width_mm / texel));
        cv::polylines(mask, pts, false, cv::Scalar(1.0), th, cv::LINE_AA, 2);
    }
}

}  // namespace

bool TissueTexture::generate(const TissueSpec& spec, double u0, double v0, double texel, int w,
                             int h, std::uint64_t seed, std::string& error) {
    u0_ = u0;
    v0_ = v0;
    texel_ = texel;
    Rng rng(seed);
    // Colour fields, all drawn whatever the amounts, so changing one amount keeps the rest.
    const cv::Mat lobe = octave(rng, w, h, texel, 30), mid = octave(rng, w, h, texel, 9),
                  fine = octave(rng, w, h, texel, 2.5), pinkn = octave(rng, w, h, texel, 22),
                  fatn = octave(rng, w, h, texel, 16), fat2 = octave(rng, w, h, texel, 5),
                  bump1 = octave(rng, w, h, texel, 5), bump2 = octave(rng, w, h, texel, 1.6),
                  bump3 = octave(rng, w, h, texel, 0.7), wetn = octave(rng, w, h, texel, 8);
    cv::Mat vessels = cv::Mat::zeros(h, w, CV_32F);
    draw_vessels(rng, vessels, texel, spec.vessels);
    cv::GaussianBlur(vessels, vessels, cv::Size(0, 0), std::max(0.5, 0.25 / texel));
    cv::Mat blood = cv::Mat::zeros(h, w, CV_32F);
    const int stains = static_cast<int>(spec.blood * w * texel * h * texel / 600.0);
    for (int i = 0; i < stains; ++i) {
        // One draw per statement, in the order x86-64 evaluated them (see draw_vessels).
        const int cy = static_cast<int>(rng.uniform(0, h));
        const cv::Point c(static_cast<int>(rng.uniform(0, w)), cy);
        const double r = rng.uniform(1.0, 7.0) / texel;
        const double angle = rng.uniform(0, 180);
        const double aspect = rng.uniform(0.4, 1.0);
        cv::ellipse(blood, c, cv::Size(std::max(1, cvRound(r)), std::max(1, cvRound(r * aspect))),
                    angle, 0, 360, cv::Scalar(1.0), -1, cv::LINE_AA);
    }
    cv::GaussianBlur(blood, blood, cv::Size(0, 0), std::max(0.7, 0.8 / texel));

    cv::Mat photo;
    if (!spec.image.empty()) {
        const cv::Mat img = cv::imread(spec.image, cv::IMREAD_COLOR);
        if (img.empty()) {
            error = spec.image + ": cannot read the tissue image";
            return false;
        }
        cv::resize(img, photo, cv::Size(w, h), 0, 0, cv::INTER_AREA);
    }
    cv::Mat height(h, w, CV_32F);
    tex_.create(h, w, CV_32FC(6));
    // Linear BGR palette: dark red liver, pink peritoneum, deep red, yellow fat.
    const float liver[3] = {0.11f, 0.08f, 0.31f}, pink[3] = {0.30f, 0.25f, 0.55f},
                deep[3] = {0.05f, 0.03f, 0.19f}, fat[3] = {0.17f, 0.36f, 0.62f},
                vessel[3] = {0.05f, 0.008f, 0.16f}, red[3] = {0.008f, 0.004f, 0.13f};
    const float fat_th = static_cast<float>(0.85 - 1.3 * spec.fat);
    for (int y = 0; y < h; ++y) {
        float* t = tex_.ptr<float>(y);
        for (int x = 0; x < w; ++x, t += 6) {
            const float l = lobe.at<float>(y, x), m = mid.at<float>(y, x), f = fine.at<float>(y, x);
            const float s1 = smoothstep(-0.7f, 0.7f, 0.7f * l + 0.3f * m);
            const float s2 = smoothstep(-0.1f, 0.8f, pinkn.at<float>(y, x)) * 0.85f;
            const float sf = spec.fat > 0
                                 ? smoothstep(fat_th, fat_th + 0.55f,
                                              fatn.at<float>(y, x) + 0.35f * fat2.at<float>(y, x))
                                 : 0.0f;
            const float ve = std::min(1.0f, vessels.at<float>(y, x)) * 0.75f;
            const float bl = std::min(1.0f, blood.at<float>(y, x));
            float c[3];
            for (int k = 0; k < 3; ++k) {
                float v = deep[k] + s1 * (liver[k] - deep[k]);
                v += s2 * (pink[k] - v);
                v += sf * (fat[k] * (0.85f + 0.3f * m) - v);
                v *= (0.9f + 0.2f * f + 0.12f * m) * (0.8f + 0.2f * l);
                v += ve * (1 - 0.6f * sf) * (vessel[k] - v);
                v += bl * (red[k] - v);
                c[k] = v;
            }
            if (!photo.empty()) {
                const cv::Vec3b p = photo.at<cv::Vec3b>(y, x);
                for (int k = 0; k < 3; ++k) c[k] = srgb_to_linear(p[k] / 255.0f);
            }
            t[0] = c[0];
            t[1] = c[1];
            t[2] = c[2];
            const float wet = static_cast<float>(spec.wetness) *
                              (0.1f + 0.9f * smoothstep(0.0f, 0.7f, wetn.at<float>(y, x)));
            t[3] = std::min(1.5f, wet * (1 - 0.5f * sf) + 0.8f * bl);
            // Height in mm: soft lobes, fine wrinkles, raised vessels, flat fat.
            height.at<float>(y, x) = 0.6f * bump1.at<float>(y, x) + 0.12f * bump2.at<float>(y, x) +
                                     0.04f * bump3.at<float>(y, x) + 0.15f * ve +
                                     0.4f * sf * fat2.at<float>(y, x);
        }
    }
    cv::Mat gu, gv;
    cv::Sobel(height, gu, CV_32F, 1, 0, 3, 1.0 / (8.0 * texel), 0, cv::BORDER_REFLECT);
    cv::Sobel(height, gv, CV_32F, 0, 1, 3, 1.0 / (8.0 * texel), 0, cv::BORDER_REFLECT);
    for (int y = 0; y < h; ++y) {
        float* t = tex_.ptr<float>(y);
        for (int x = 0; x < w; ++x, t += 6) {
            t[4] = gu.at<float>(y, x);
            t[5] = gv.at<float>(y, x);
        }
    }
    return true;
}

}  // namespace endotower::scene::detail
