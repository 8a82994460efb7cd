// GestureClassifier: the book's feed-forward network (ch. 3): GestureFeatures in,
// one of the seven gestures out (open/closed grasper, open/closed scissors, cross,
// triangle, double triangle; kGestureLabels order = the book's output order).
//
// Network: OpenCV ml::ANN_MLP, inputs -> `hidden` (20) -> outputs, symmetric sigmoid units,
// trained by backpropagation (`iterations` 3000 epochs, rate 0.05, momentum 0.1)
// towards the book's targets 0.9 for the class and 0.1 for the others. Inputs are
// scaled by the training set's mean and spread (OpenCV's own input scaling).
// `features`: kBook = the six features and seven outputs (the book's 6-20-7
// baseline), kExtended = nine features and an eighth output, "not a tool" (tissue
// regions the segmentation mistakes for one; trained on such regions), so 9-20-8: the
// improved classifier (docs/gestures.md); kTopology = those nine and the two hole
// features, 11-20-8 (the holes tell cross, triangle and double triangle apart);
// kProfile (shipped) = a topology model and a third network, 31-20-8, on those eleven
// and the profile across the shaft (GestureFeatures), whose outputs are averaged with
// the single-tool network's. The segmentation method the model was trained on, and for
// the likelihood method its mask threshold (`threshold`, default 128 = even odds) and
// one tool's (`single_threshold`, GestureSegmenterParams), are stored with it, so the
// firmware segments the same way.
//
// Two networks (`two_tool_network`, extended, topology or profile): a region with two rim
// entries (GestureBlob::entries 2: two tools meeting, or one along the rim) is read first
// by the two-tool network, which alone names cross, triangle and double triangle; where
// it names none of those the single-tool network decides (a two-tool class from it
// counts as none); a region with one entry is one tool: the single-tool network's best
// single-tool class or "not a tool". Samples marked `single_tool_only` (a new
// single-tool pose) train only the single-tool network, so they cannot cost the
// two-tool gestures; samples marked `two_tool_only` (more crossings) only the two-tool
// network; both networks learn from every other sample (docs/gestures.md, "Two
// networks").
//
// File: "ETGES1\n", "features book|extended|topology|profile\n",
// "segmentation morphology|likelihood\n" (likelihood with a threshold other than 128:
// "segmentation likelihood threshold N\n", 1 <= N <= 255; with a one-tool mask
// "segmentation likelihood threshold N single M\n", N < M <= 255), the network as OpenCV
// FileStorage YAML (node opencv_ml_ann_mlp; the two-tool network, when there is one, node
// two_tool_ann_mlp; the profile network, with the profile features only and then required,
// profile_ann_mlp), then "fnv1a " and the FNV-1a 64-bit hash of everything before it as 16
// hex digits and "\n" (the same non-standard offset basis as tool_likelihood.hpp's).
// parse()/load() refuse another header, a hash mismatch, a malformed threshold, or a
// network that is not features-hidden-classes, with a message naming the file (the network
// must be 6-N-7, 9-N-8 or 11-N-8, the profile network 31-N-8, 2 <= N <= kGestureMaxHidden,
// every list as long as the layers make it). serialise() gives the bytes (the caller
// writes them atomically). classify() is for the per-frame path: no exceptions, no
// allocation.
#pragma once

#include <array>
#include <memory>
#include <string>
#include <vector>

#include "endotower/vision/gesture_features.hpp"
#include "endotower/vision/gesture_segmenter.hpp"

namespace cv::ml {
class ANN_MLP;
}

namespace endotower::vision {

constexpr int kGestureLabelCount = 7;
inline constexpr std::array<const char*, kGestureLabelCount> kGestureLabels = {
    "open_grasper", "closed_grasper", "open_scissors",  "closed_scissors",
    "cross",        "triangle",       "double_triangle"};
int gesture_label_index(const std::string& label);  // -1 if not one of kGestureLabels
constexpr int kOpenGrasperLabel = 0;                // kGestureLabels[0]
// The first four labels are one tool's (open/closed grasper, open/closed scissors); cross,
// triangle, double triangle are made with two.
constexpr int kSingleToolLabels = 4;
constexpr bool two_tool_gesture(int label) {
    return label >= kSingleToolLabels && label < kGestureLabelCount;
}

// The features of the single-tool and two-tool networks: the profile set's are the
// topology set's, and a third network reads all 31 (the stations across the shaft);
// the single-tool decision is the mean of its outputs and the single-tool network's
// (measured: the profile alone lost fixed orientations and cost the two-tool gestures;
// docs/gestures.md).
constexpr GestureFeatureSet base_feature_set(GestureFeatureSet s) {
    return s == GestureFeatureSet::kProfile ? GestureFeatureSet::kTopology : s;
}

constexpr int kGestureMaxHidden = 1000;  // hidden units; OpenCV needs at least 2

struct GestureTrainParams {
    GestureFeatureSet features = GestureFeatureSet::kBook;
    GestureSegmentation segmentation = GestureSegmentation::kLikelihood;
    int threshold = 128;  // likelihood: the mask threshold (GestureSegmenterParams::threshold)
    int single_threshold = 0;  // likelihood: one tool's mask (GestureSegmenterParams); 0: none
    int hidden = 20;
    int iterations = 3000;
    bool two_tool_network = false;  // a second network for two-tool regions (extended)
    bool rprop = false;  // RPROP (batch) instead of the book's sequential backpropagation
};

constexpr int kNotATool = kGestureLabelCount;  // the extended classifier's eighth class

// The one-tool mask's threshold `p` implies: 0 where there is none (morphology, or not
// above the mask threshold).
constexpr int single_mask_threshold(const GestureTrainParams& p) {
    return p.segmentation == GestureSegmentation::kLikelihood && p.single_threshold > p.threshold
               ? p.single_threshold
               : 0;
}

// The segmenter the networks of `p` read: its method and threshold, and the profile
// measured for the profile features; GestureSegmenterParams' defaults otherwise.
GestureSegmenterParams gesture_segmenter_params(const GestureTrainParams& p);

struct GestureSample {
    GestureFeatures features;
    int label = 0;                  // index in kGestureLabels, or kNotATool
    int entries = 1;                // the region's rim entries (GestureBlob::entries)
    bool single_tool_only = false;  // trains only the single-tool network (two networks)
    bool two_tool_only = false;     // trains only the two-tool network (two networks)
};

struct GestureResult {
    int label = -1;         // index in kGestureLabels
    double confidence = 0;  // the winning output, clamped to 0..1
};

class GestureClassifier {
public:
    GestureClassifier();
    ~GestureClassifier();
    bool trained() const;
    GestureFeatureSet features() const { return features_; }
    GestureSegmentation segmentation() const { return segmentation_; }
    // The likelihood segmentation's mask threshold the model was trained with.
    int segmentation_threshold() const { return threshold_; }
    // The one-tool mask's threshold (GestureSegmenterParams::single_threshold); 0: none.
    int single_tool_threshold() const { return single_threshold_; }
    // The segmenter the model was trained on (gesture_segmenter_params of its settings).
    GestureSegmenterParams segmenter_params() const;

    bool train(const std::vector<GestureSample>& samples, const GestureTrainParams& params,
               std::string& error);
    // Trains the two-tool network anew (samples not single_tool_only) and keeps the
    // single-tool and profile networks as they are: a trained two-network model, the
    // same features and segmentation in `params`.
    bool retrain_two_tool(const std::vector<GestureSample>& samples,
                          const GestureTrainParams& params, std::string& error);
    // `entries`: the region's rim entries; 2 uses the two-tool network when there is one.
    GestureResult classify(const GestureFeatures& f, int entries = 1) const;
    bool has_two_tool_network() const;

    std::string serialise() const;
    bool parse(const std::string& bytes, const std::string& name, std::string& error);
    bool load(const std::string& path, std::string& error);

private:
    // one_tool: a two-tool class is not an answer; the best of the others is.
    // two_tool_network: that network; else the single-tool one (and the profile one).
    GestureResult run(bool two_tool_network, const GestureFeatures& f, bool one_tool) const;
    struct Net;
    std::unique_ptr<Net> net_;
    GestureFeatureSet features_ = GestureFeatureSet::kBook;
    GestureSegmentation segmentation_ = GestureSegmentation::kLikelihood;
    int threshold_ = 128;
    int single_threshold_ = 0;
};

}  // namespace endotower::vision
