// GestureSegmenter: finds the tool tips whose shape the gesture classifier reads.
//
// Per frame, on the frame reduced to `analysis_width` (640) columns:
//  1. a tool mask, by one of two methods (`method`):
//     kMorphology (the book, eq. 3.3-3.5): grey A = 255 - luma (tools are the dark
//       objects here, the book's were the bright ones); background reduction
//       A - (A o B1) with a square B1 of `large_element_fraction` (0.1) x width, larger
//       than a tool; modified background reduction A + (A o B2) with a square B2 of
//       `small_element` (3) px, smaller than a tool (saturating); threshold at
//       `high_threshold` (200);
//     kLikelihood (default; measured better, docs/gestures.md): the learned tool
//       probability (ToolLikelihood, borrowed), 5x5 Gaussian, threshold `threshold`
//       (128 = even odds), 3x3 opening;
//     both then only inside the lit field of view (as LikelihoodToolTracker);
//     kLikelihood with `single_threshold` above `threshold` (default 0: off): a second
//     mask of the same smoothed probability at that threshold, for one tool (below, 4);
//  2. 8-connected regions of at least `min_area_fraction` (0.002) of the picture that
//     reach within `border_touch_fraction` (0.06) x width of its edge (tools enter
//     from outside the picture) and whose length (principal axis, second moments) is
//     at least `min_elongation` (2.5) x their width; the largest `kMaxBlobs` (2);
//  3. per region, the tip: the pixel farthest from where it enters (from both entries
//     when two tools cross and meet the rim twice; of two parts near the rim, one that
//     does not come within `entry_rim_fraction` (0.0125) x width of it while the other
//     does is no entry: an open jaw's end); the shaft radius r: the largest
//     distance-transform value near the entry; the tip window: the region's pixels
//     within `window_radii` (8) x r of the tip (jaws and a little shaft), on which
//     the features are measured (GestureFeatures: the book's six, the extras, the holes,
//     and, when `profile` is set, the profile across the axis from the tip to its
//     entry, in units of r; else those stay 0); the arms: the region's parts that
//     cross the window's edge, and for a region entering twice also those crossing
//     the circle of `window_radii` x the thinner entry's radius (`thin_arms`);
//  4. with `single_threshold`: a region that enters once is measured (3) on the largest
//     region of the second mask inside it (the mask in the box of such regions alone) if
//     that is a tool's tip entering once, else on the first mask; 3 only checks that its
//     tip window holds a blob. The higher threshold joins less of the tissue's sheen to
//     a lone tool's jaws; crossing tools stay the first mask's (docs/gestures.md, "Two
//     masks").
// Output: up to kMaxBlobs blobs with the tip in the input frame's pixels.
// Needs a BGR24 frame; anything else gives no blobs. No exceptions; buffers are set up
// in configure(), and with `threads` = 2 a helper thread that, inside segment(), takes
// the lower half of the rows of the per-pixel passes (reduction, grey value, tool
// probability) and shares the regions (each thread takes the next one when free): the
// same bytes and blobs as one thread. Own code (BlockMean, MaskOps, ContourTracer)
// gives the bytes of the OpenCV calls it replaces, without their allocations
// (docs/gestures.md#speed).
#pragma once

#include <array>
#include <memory>
#include <span>

#include "endotower/hal/frame.hpp"
#include "endotower/vision/gesture_features.hpp"
#include "endotower/vision/tool_likelihood.hpp"
#include "endotower/vision/tool_pose.hpp"

namespace endotower::vision {

enum class GestureSegmentation { kMorphology, kLikelihood };

struct GestureSegmenterParams {
    GestureSegmentation method = GestureSegmentation::kLikelihood;
    int analysis_width = 640;
    double large_element_fraction = 0.1;
    int small_element = 3;
    int high_threshold = 200;
    int threshold = 128;
    int single_threshold = 0;  // one tool's mask (4); 0 or <= threshold: none
    double min_area_fraction = 0.002;
    double border_touch_fraction = 0.06;
    double min_elongation = 2.5;
    double window_radii = 8.0;
    double entry_rim_fraction = 0.0125;  // an entry reaches this near the rim (x width)
    bool profile = false;  // measure the profile features (a kProfile model reads them)
    int threads = 2;       // 2: a helper thread shares segment()'s work (above; 1 if none starts)
};

struct GestureBlob {
    Point2 tip;            // input frame pixels
    double radius_px = 0;  // shaft radius, input frame pixels
    int entries = 1;       // rim entries: 2 = two tools in one region
    int arms = 0;          // the region's runs across the tip window's edge
    int thin_arms = 0;     // entering twice: the runs across the thinner shaft's window
    GestureFeatures features;
};

class GestureSegmenter {
public:
    static constexpr std::size_t kMaxBlobs = 2;
    // `model` is borrowed and must outlive the segmenter; it may be null for kMorphology.
    GestureSegmenter(const ToolLikelihood* model, GestureSegmenterParams params = {});
    ~GestureSegmenter();
    const GestureSegmenterParams& params() const { return params_; }
    void configure(const hal::FrameFormat& format);
    std::size_t segment(const hal::Frame& frame, std::span<GestureBlob, kMaxBlobs> out);
    // The last segment()'s tool mask at the analysis size (before the region filter):
    // row-major, mask_width() bytes a row, 0 or 255 (the first mask, at `threshold`); empty
    // before configure().
    std::span<const std::uint8_t> mask() const;
    int mask_width() const;

private:
    struct Work;
    const ToolLikelihood* model_;
    GestureSegmenterParams params_;
    std::unique_ptr<Work> work_;
};

}  // namespace endotower::vision
