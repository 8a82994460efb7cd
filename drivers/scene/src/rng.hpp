// Deterministic random numbers for the simulator (private). Every consumer draws from
// its own stream, derived from the recording's seed and a fixed tag, so that adding
// noise does not change the texture, and a frame's draws do not depend on the order
// in which frames are rendered. Conversions to doubles and Gaussians are written out
// here (not std::*_distribution, whose algorithms the standard leaves open), so the
// bytes are the same with any standard library.
#pragma once

#include <cmath>
#include <cstdint>
#include <random>

namespace endotower::scene::detail {

inline std::uint64_t splitmix64(std::uint64_t x) {
    x += 0x9E3779B97F4A7C15ull;
    x = (x ^ (x >> 30)) * 0xBF58476D1CE4E5B9ull;
    x = (x ^ (x >> 27)) * 0x94D049BB133111EBull;
    return x ^ (x >> 31);
}

// Stream seed for (seed, tag, index).
inline std::uint64_t stream_seed(std::uint64_t seed, std::uint64_t tag, std::uint64_t index = 0) {
    return splitmix64(splitmix64(splitmix64(seed) ^ tag) ^ index);
}

class Rng {
public:
    explicit Rng(std::uint64_t seed) : engine_(seed) {}
    // Uniform in [0, 1) with 53 random bits.
    double uniform() { return static_cast<double>(engine_() >> 11) * 0x1.0p-53; }
    double uniform(double lo, double hi) { return lo + (hi - lo) * uniform(); }
    // Standard normal, Box-Muller (both values used).
    double gauss() {
        if (has_spare_) {
            has_spare_ = false;
            return spare_;
        }
        const double u1 = 1.0 - uniform(), u2 = uniform();
        const double r = std::sqrt(-2.0 * std::log(u1)), a = 2.0 * M_PI * u2;
        spare_ = r * std::sin(a);
        has_spare_ = true;
        return r * std::cos(a);
    }

private:
    std::mt19937_64 engine_;
    double spare_ = 0;
    bool has_spare_ = false;
};

// Stream tags.
constexpr std::uint64_t kTagTexture = 1, kTagTexture2 = 2, kTagWander = 3, kTagNoise = 4,
                        kTagFlash = 5, kTagSmoke = 6;

}  // namespace endotower::scene::detail
