// SceneRenderer: renders the frames of a scenario with their exact ground truth.
//
// Each displayed pixel is undistorted (the camera's inverse mapping), its ray cast
// through the pinhole into the 3-D scene (tissue plane or calibration target, tools,
// distractors, tissue flaps), shaded with the light at the lens, then the optics
// (vignetting, field-of-view circle, blur), smoke, flashes and sensor noise are
// applied. Edge pixels are re-cast with 3x3 sub-samples; motion blur averages
// sub-frame instants over the exposure. Truth is computed from the same 3-D state at
// the frame's instant (mid-exposure).
//
// Deterministic: the output depends only on the scenario and the seed (separate
// random streams per purpose and per frame), not on the order frames are rendered in
// or on the number of threads.
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "endotower/scene/camera.hpp"
#include "endotower/scene/scenario.hpp"
#include "endotower/scene/truth.hpp"

namespace endotower::scene {

struct Image {
    int width = 0, height = 0;
    std::vector<std::uint8_t> bgr;  // row-major, 3 bytes per pixel, no padding
};

class SceneRenderer {
public:
    SceneRenderer();
    ~SceneRenderer();
    // Builds the camera, the motions and the tissue texture; false with `error` if a
    // file the scenario names cannot be used.
    bool init(const Scenario& scenario, std::uint64_t seed, std::string& error);
    const CameraModel& camera() const;
    const Scenario& scenario() const;
    int frames() const;
    // Renders frame `index` (0 <= index < frames()) into `image` and fills `truth`.
    void render(int index, Image& image, FrameTruth& truth);
    // Per pixel of the last rendered frame, which tool it shows: 0 none (tissue,
    // target, distractor, flap, outside the field of view), 1.. the tool's index + 1,
    // kMixedLabel where motion blur mixes surfaces. Row-major, width x height.
    static constexpr std::uint8_t kMixedLabel = 255;
    void tool_labels(std::vector<std::uint8_t>& out) const;

private:
    struct Impl;
    std::unique_ptr<Impl> impl_;
};

}  // namespace endotower::scene
