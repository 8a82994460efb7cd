// Writes a scenario's recording: DIR/frames/000000.png ... (lossless, the input
// `endotower sim --input DIR/frames` reads), DIR/truth.jsonl (docs/truth.md) and
// DIR/scenario.yaml (a byte copy of the scenario file); with `labels`, DIR/labels/
// 000000.png ... (8-bit, SceneRenderer::tool_labels) for training per-pixel models.
//
// Atomic: everything is written into DIR.tmp-XXXXXX beside DIR and renamed to DIR at
// the end; an existing DIR is replaced only if it is empty or an earlier recording
// (holds truth.jsonl), else refused.
//
// Options override the file: seed, frame count, output size, and a duration scale
// (every duration in frames multiplied, for the bigger report versions of a suite).
#pragma once

#include <cstdint>
#include <optional>
#include <string>

namespace endotower::scene {

struct RecordingOptions {
    std::string scenario_path, out_dir;
    std::optional<std::uint64_t> seed;
    int frames = 0;             // 0 = the scenario's (after scaling)
    int width = 0, height = 0;  // 0 = the scenario's
    double scale = 1.0;
    bool labels = false;  // also DIR/labels/000000.png: per-pixel tool labels (tool_labels)
};

struct RecordingStats {
    int frames = 0;
    double render_ms_per_frame = 0, write_ms_per_frame = 0, setup_ms = 0;
};

enum class RecordingResult { kOk, kBadInput, kFailed };

RecordingResult write_recording(const RecordingOptions& options, RecordingStats& stats,
                                std::string& error);

}  // namespace endotower::scene
