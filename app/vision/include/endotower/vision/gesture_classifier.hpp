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
// improved classifier (docs/gestures.md). The segmentation method the model was
// trained on is stored with it, so the firmware segments the same way.
//
// File: "ETGES1\n", "features book|extended\n", "segmentation morphology|likelihood\n",
// the network as OpenCV FileStorage YAML, then "fnv1a " and the FNV-1a 64-bit hash of
// everything before it as 16 hex digits and "\n". parse()/load() refuse another
// header, a hash mismatch, or a network that is not features-hidden-7, with a
// message naming the file (the network must be 6-N-7 or 9-N-8). serialise() gives the bytes (the
// caller writes them atomically). classify() is for the per-frame path: no exceptions, no
// allocation.
#pragma once

#include <array>
#include <memory>
#include <string>
#include <vector>

#include "endotower/vision/gesture_features.hpp"
#include "endotower/vision/gesture_segmenter.hpp"

namespace endotower::vision {

constexpr int kGestureLabelCount = 7;
inline constexpr std::array<const char*, kGestureLabelCount> kGestureLabels = {
    "open_grasper", "closed_grasper", "open_scissors",  "closed_scissors",
    "cross",        "triangle",       "double_triangle"};
int gesture_label_index(const std::string& label);  // -1 if not one of kGestureLabels

struct GestureTrainParams {
    GestureFeatureSet features = GestureFeatureSet::kBook;
    GestureSegmentation segmentation = GestureSegmentation::kLikelihood;
    int hidden = 20;
    int iterations = 3000;
};

constexpr int kNotATool = kGestureLabelCount;  // the extended classifier's eighth class

struct GestureSample {
    GestureFeatures features;
    int label = 0;  // index in kGestureLabels, or kNotATool
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

    bool train(const std::vector<GestureSample>& samples, const GestureTrainParams& params,
               std::string& error);
    GestureResult classify(const GestureFeatures& f) const;

    std::string serialise() const;
    bool parse(const std::string& bytes, const std::string& name, std::string& error);
    bool load(const std::string& path, std::string& error);

private:
    struct Net;
    std::unique_ptr<Net> net_;
    GestureFeatureSet features_ = GestureFeatureSet::kBook;
    GestureSegmentation segmentation_ = GestureSegmentation::kLikelihood;
};

}  // namespace endotower::vision
