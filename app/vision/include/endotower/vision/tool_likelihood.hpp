// ToolLikelihood: a learned per-pixel probability that a pixel shows a surgical tool,
// from its colour (issue 5's "go beyond the book": the book's grey edges lock onto
// tissue folds and caption text; tools differ from tissue first of all in colour).
//
// Feature: the pixel's chromaticity and brightness, quantised: b/(b+g+r) and
// g/(b+g+r) in 64 steps each, (b+g+r)/3 in 16 steps: 65536 cells. Chromaticity
// does not change with the light level, so one table serves the book's 0-100 %
// light bands. Training counts tool and background pixels per cell, smooths the
// counts over neighbouring cells (3x3x3 box, so unseen colours borrow from their
// neighbours) and stores P(tool | cell) with equal priors as 0..255.
//
// File (written atomically by the caller's write): "ETLIK1\n", then 65536 bytes of
// probabilities, then the FNV-1a 64-bit hash of those bytes as 16 hex digits and
// "\n" (its offset basis is 1469598103934665603, a digit short of the standard one; kept
// so the files already written stay valid). load() refuses any other size, header or hash with a
// message naming the file. cell() is exact integer arithmetic, round(63 b / s) with s = b + g + r,
// its two divisions by s done as multiplications by 2^40 / s rounded up (the same cell as the
// divisions for every colour; tested on all 2^24), so probability() is cheap per pixel.
#pragma once

#include <algorithm>
#include <array>
#include <cstdint>
#include <string>

#include "endotower/hal/frame.hpp"

namespace endotower::vision {

class ToolLikelihood {
public:
    static constexpr int kChroma = 64, kLevels = 16, kCells = kChroma * kChroma * kLevels;

    static int cell(std::uint8_t b, std::uint8_t g, std::uint8_t r) {
        const unsigned s = b + g + r;
        if (s == 0) return 0;
        const std::uint64_t m = kReciprocal[s];
        const int cb = static_cast<int>(((b * (kChroma - 1u) + s / 2) * m) >> 40);
        const int cg = static_cast<int>(((g * (kChroma - 1u) + s / 2) * m) >> 40);
        const int lv = std::min<int>(kLevels - 1, static_cast<int>(s * kLevels / 766));
        return (cb * kChroma + cg) * kLevels + lv;
    }
    // cell() of `n` BGR pixels into `out`, vectorised (the same cells: the divisions in
    // single precision, exact here since the quotients are below 64 and the divisors
    // below 766; tested on all 2^24 colours). For the per-frame loops over whole rows.
    static void cells(const std::uint8_t* bgr, std::uint16_t* out, int n);
    std::uint8_t probability(std::uint8_t b, std::uint8_t g, std::uint8_t r) const {
        return table_[cell(b, g, r)];
    }
    const std::array<std::uint8_t, kCells>& table() const { return table_; }
    bool trained() const { return trained_; }

    // Training: labels are per pixel 0 background, 1..254 tool, 255 ignored (mixed);
    // `weight` scales this image's counts (e.g. real frames against many simulated ones).
    // `gains` (b, g, r) scale the pixels first: white-balance augmentation, so a model
    // trained on the simulator's neutral greys also knows tinted real ones.
    void add(const hal::Frame& bgr, const std::uint8_t* labels, double weight = 1.0,
             const std::array<double, 3>& gains = {1.0, 1.0, 1.0});
    // Computes the table from the counts; false when either class has no pixels.
    bool finish(std::string& error);

    // Adds an image file with its label file (same size; a label PNG of `scene
    // --labels`, or a binary tool mask where nonzero = tool). Errors name the file.
    // `augment` > 0 also adds that many copies with random channel gains in
    // 1 +- `gain_spread` (deterministic: drawn from `seed`).
    bool add_files(const std::string& image, const std::string& labels, double weight,
                   std::string& error, int augment = 0, double gain_spread = 0.15,
                   std::uint64_t seed = 1);

    std::string serialise() const;
    bool load(const std::string& path, std::string& error);
    bool parse(const std::string& bytes, const std::string& name, std::string& error);

private:
    static constexpr std::array<std::uint64_t, 766> kReciprocal = [] {
        std::array<std::uint64_t, 766> r{};
        for (std::uint64_t s = 1; s < r.size(); ++s) r[s] = ((std::uint64_t{1} << 40) + s - 1) / s;
        return r;
    }();
    std::array<double, kCells> tool_{}, background_{};
    std::array<std::uint8_t, kCells> table_{};
    bool trained_ = false;
};

}  // namespace endotower::vision
