// ToolLikelihood: counting, smoothing and the model file (tool_likelihood.hpp).
#include "endotower/vision/tool_likelihood.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <sstream>
#include <vector>

#include "wide_vectors.hpp"

namespace endotower::vision {

namespace {

constexpr char kMagic[] = "ETLIK1\n";
constexpr std::size_t kMagicLen = sizeof(kMagic) - 1;

std::uint64_t fnv1a(const std::uint8_t* p, std::size_t n) {
    std::uint64_t h = 1469598103934665603ull;
    for (std::size_t i = 0; i < n; ++i) h = (h ^ p[i]) * 1099511628211ull;
    return h;
}

}  // namespace

// A quotient below 64 with a divisor below 766 is within 64 x 2^-24 of the true one in
// single precision, closer than the 1/765 that separates a non-integer one from the next
// integer: truncating it gives the integer division (an integer quotient is exact).
// b = g = r = 0 gives cell 0 with the divisor 1, as cell() does.
ENDOTOWER_WIDE_VECTORS void ToolLikelihood::cells(const std::uint8_t* __restrict bgr,
                                                  std::uint16_t* __restrict out, int n) {
    // Indexed loads and no std::min/max: the form GCC vectorises (8 pixels a step).
    for (int x = 0; x < n; ++x) {
        const int b = bgr[3 * x], g = bgr[3 * x + 1], r = bgr[3 * x + 2], s = b + g + r;
        const float d = static_cast<float>(s | (s == 0));
        const int cb = static_cast<int>(static_cast<float>(b * (kChroma - 1) + (s >> 1)) / d);
        const int cg = static_cast<int>(static_cast<float>(g * (kChroma - 1) + (s >> 1)) / d);
        const int lv = static_cast<int>(static_cast<float>(s * kLevels) / 766.0f);
        out[x] = static_cast<std::uint16_t>((cb * kChroma + cg) * kLevels +
                                            (lv < kLevels - 1 ? lv : kLevels - 1));
    }
}

void ToolLikelihood::add(const hal::Frame& f, const std::uint8_t* labels, double weight,
                         const std::array<double, 3>& gains) {
    if (f.format.pixel_format != hal::PixelFormat::kBgr24) return;
    std::array<std::array<std::uint8_t, 256>, 3> lut;
    for (int c = 0; c < 3; ++c)
        for (int v = 0; v < 256; ++v)
            lut[c][v] = static_cast<std::uint8_t>(std::min(255L, std::lround(v * gains[c])));
    for (int y = 0; y < f.format.height; ++y) {
        const std::uint8_t* p = f.data + static_cast<std::size_t>(y) * f.format.stride;
        const std::uint8_t* l = labels + static_cast<std::size_t>(y) * f.format.width;
        for (int x = 0; x < f.format.width; ++x, p += 3) {
            if (l[x] == 255) continue;
            const std::uint8_t b = lut[0][p[0]], g = lut[1][p[1]], r = lut[2][p[2]];
            if (b + g + r < 24 && l[x] == 0) continue;  // the dark surround teaches nothing
            (l[x] ? tool_ : background_)[cell(b, g, r)] += weight;
        }
    }
}

bool ToolLikelihood::finish(std::string& error) {
    double nt = 0, nb = 0;
    for (int i = 0; i < kCells; ++i) nt += tool_[i], nb += background_[i];
    if (nt <= 0 || nb <= 0) {
        error = nt <= 0 ? "no tool pixels in the training data"
                        : "no background pixels in the training data";
        return false;
    }
    // 3x3x3 box over (cb, cg, level), then P(tool) with equal priors; a small
    // pseudo-count keeps cells nobody saw at 0.5 x (their neighbours' evidence).
    auto at = [](const std::array<double, kCells>& a, int cb, int cg, int lv) {
        if (cb < 0 || cg < 0 || lv < 0 || cb >= kChroma || cg >= kChroma || lv >= kLevels)
            return 0.0;
        return a[(cb * kChroma + cg) * kLevels + lv];
    };
    const double prior = 1e-7;
    for (int cb = 0; cb < kChroma; ++cb)
        for (int cg = 0; cg < kChroma; ++cg)
            for (int lv = 0; lv < kLevels; ++lv) {
                double t = 0, b = 0;
                for (int d0 = -1; d0 <= 1; ++d0)
                    for (int d1 = -1; d1 <= 1; ++d1)
                        for (int d2 = -1; d2 <= 1; ++d2) {
                            t += at(tool_, cb + d0, cg + d1, lv + d2);
                            b += at(background_, cb + d0, cg + d1, lv + d2);
                        }
                const double pt = t / nt + prior, pb = b / nb + prior;
                table_[(cb * kChroma + cg) * kLevels + lv] =
                    static_cast<std::uint8_t>(std::lround(255.0 * pt / (pt + pb)));
            }
    trained_ = true;
    return true;
}

std::string ToolLikelihood::serialise() const {
    std::string s(kMagic, kMagicLen);
    s.append(reinterpret_cast<const char*>(table_.data()), table_.size());
    char hash[20];
    std::snprintf(hash, sizeof hash, "%016llx\n",
                  static_cast<unsigned long long>(fnv1a(table_.data(), table_.size())));
    return s + hash;
}

bool ToolLikelihood::parse(const std::string& bytes, const std::string& name, std::string& error) {
    const std::size_t want = kMagicLen + kCells + 17;
    if (bytes.compare(0, kMagicLen, kMagic) != 0) {
        error = name + ": not a tool likelihood model (expected the header ETLIK1)";
        return false;
    }
    if (bytes.size() != want) {
        error = name + ": " + std::to_string(bytes.size()) +
                " bytes, a tool likelihood model has " + std::to_string(want) +
                " (truncated or not this version)";
        return false;
    }
    const auto* table = reinterpret_cast<const std::uint8_t*>(bytes.data() + kMagicLen);
    char hash[20];
    std::snprintf(hash, sizeof hash, "%016llx\n",
                  static_cast<unsigned long long>(fnv1a(table, kCells)));
    if (bytes.compare(kMagicLen + kCells, 17, hash) != 0) {
        error = name + ": checksum mismatch (the file is corrupt)";
        return false;
    }
    std::copy(table, table + kCells, table_.begin());
    trained_ = true;
    return true;
}

bool ToolLikelihood::load(const std::string& path, std::string& error) {
    std::ifstream in(path, std::ios::binary);
    if (!in) {
        error = "cannot read the tool model " + path;
        return false;
    }
    std::stringstream s;
    s << in.rdbuf();
    return parse(s.str(), path, error);
}

}  // namespace endotower::vision
