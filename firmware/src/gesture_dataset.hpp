// Gesture training and test samples from labelled recordings: the folder of an
// `endotower scene` run (DIR/frames/NNNNNN.png and DIR/truth.jsonl, docs/truth.md)
// or a hand-labelled real clip in the same layout (a truth line per frame with the
// tools' tip_px and gesture labels).
//
// Per used frame (every `every`-th), the segmenter's blobs get the truth's label:
// the frame's two-tool `gesture` for a blob that enters the picture twice (or the only
// blob), else the single-tool `gesture` of the visible tool whose tip_px is nearest
// the blob's tip, within `match_fraction` (0.08) x frame width or `match_widths` (2) x
// the tool's width_px, whichever is larger (nearest in units of that distance; 0 widths:
// the fraction alone, the rule before 2026-11-27). Blobs without a label
// are skipped (counted in `unlabelled`), except, with `reject`, those farther than
// 3 x that distance from every visible tool's tip: vision::kNotATool (tissue taken
// for a tool). Errors name the file.
#pragma once

#include <string>
#include <vector>

#include "endotower/vision/gesture_classifier.hpp"

namespace endotower::firmware {

struct GestureDatasetStats {
    int frames = 0, blobs = 0, unlabelled = 0;
};

bool add_gesture_samples(const std::string& dir, vision::GestureSegmenter& segmenter, int every,
                         std::vector<vision::GestureSample>& out, GestureDatasetStats& stats,
                         std::string& error, double match_fraction = 0.08, bool reject = false,
                         double match_widths = 2.0);

}  // namespace endotower::firmware
