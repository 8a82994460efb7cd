#include "gesture_dataset.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <opencv2/imgcodecs.hpp>

#include "endotower/eval/truth.hpp"

namespace endotower::firmware {

bool add_gesture_samples(const std::string& dir, vision::GestureSegmenter& segmenter, int every,
                         std::vector<vision::GestureSample>& out, GestureDatasetStats& stats,
                         std::string& error, double match_fraction, bool reject,
                         double match_widths) {
    namespace fs = std::filesystem;
    const fs::path truth_path = fs::path(dir) / "truth.jsonl", frames = fs::path(dir) / "frames";
    if (!fs::is_directory(frames)) {
        error = dir + ": no frames/ folder (a recording of 'endotower scene')";
        return false;
    }
    std::vector<eval::TruthFrame> truth;
    if (!eval::read_truth(truth_path.string(), truth, error)) return false;
    hal::FrameFormat configured{};
    std::array<vision::GestureBlob, vision::GestureSegmenter::kMaxBlobs> blobs{};
    for (std::size_t i = 0; i < truth.size(); i += static_cast<std::size_t>(std::max(1, every))) {
        const eval::TruthFrame& t = truth[i];
        char name[32];
        std::snprintf(name, sizeof name, "%06lld.png", static_cast<long long>(t.frame));
        const std::string path = (frames / name).string();
        cv::Mat img = cv::imread(path, cv::IMREAD_COLOR);
        if (img.empty()) {
            error = path + ": missing or not an image (truth line for frame " +
                    std::to_string(t.frame) + ")";
            return false;
        }
        hal::Frame f;
        f.format = {img.cols, img.rows, static_cast<int>(img.step), hal::PixelFormat::kBgr24};
        f.data = img.data;
        if (f.format.width != configured.width || f.format.height != configured.height) {
            segmenter.configure(f.format);
            configured = f.format;
        }
        const std::size_t n = segmenter.segment(f, blobs);
        ++stats.frames;
        // A tool's tip matches a blob's within the fraction of the frame width or, for a
        // tool drawn larger than that, twice its width (the book's tracking rule): an open
        // 10 mm grasper near the scope reaches its farthest jaw end, the blob's tip, 60-80 px
        // from the truth's tip between the jaws (docs/gestures.md, "Tools from anywhere").
        auto near = [&](const eval::TruthTool& tool) {
            return std::max(match_fraction * img.cols, match_widths * tool.width_px);
        };
        for (std::size_t b = 0; b < n; ++b) {
            ++stats.blobs;
            int label = -1;
            if (t.gesture && (blobs[b].entries == 2 || n == 1)) {
                label = vision::gesture_label_index(*t.gesture);
            } else if (!t.gesture) {
                double best = 1.0;  // the nearest tip, as a share of its match distance
                for (const eval::TruthTool& tool : t.tools) {
                    const double d =
                        std::hypot(tool.tip_px.x - blobs[b].tip.x, tool.tip_px.y - blobs[b].tip.y) /
                        near(tool);
                    if (tool.visible && !tool.gesture.empty() && d < best)
                        best = d, label = vision::gesture_label_index(tool.gesture);
                }
            }
            if (label < 0 && reject) {
                // Far from every tool: tissue the segmentation took for a tool.
                bool far = true;
                for (const eval::TruthTool& tool : t.tools)
                    far = far && (!tool.visible ||
                                  std::hypot(tool.tip_px.x - blobs[b].tip.x,
                                             tool.tip_px.y - blobs[b].tip.y) > 3 * near(tool));
                if (far) label = vision::kNotATool;
            }
            if (label < 0) {
                ++stats.unlabelled;
                continue;
            }
            out.push_back({blobs[b].features, label, blobs[b].entries});
        }
    }
    return true;
}

}  // namespace endotower::firmware
