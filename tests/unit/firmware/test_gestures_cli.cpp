// Tool gestures end to end (issue 6): the shipped model on simulator suites never
// used in training (each at its own seed), train-gestures, a corrupt model in `sim`,
// and the confusion from `eval` on a rendered suite.
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <array>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>
#include <sstream>

#include "endotower/eval/truth.hpp"
#include "endotower/vision/gesture_classifier.hpp"
#include "endotower/vision/gesture_segmenter.hpp"
#include "gesture_dataset.hpp"
#include "gesture_model_edit.hpp"

namespace fs = std::filesystem;
using namespace endotower;

namespace {

const std::string kRoot = ENDOTOWER_SOURCE_DIR;
const std::string kModels = kRoot + "/board/sim/models/";

std::string slurp(const fs::path& p) {
    std::ifstream f(p);
    std::stringstream s;
    s << f.rdbuf();
    return s.str();
}

class Gestures : public ::testing::Test {
protected:
    static fs::path dir() {
        return fs::temp_directory_path() / ("endotower_gestures_" + std::to_string(::getpid()));
    }
    static int run(const std::string& args, const std::string& tag = "out") {
        const std::string cmd = std::string(ENDOTOWER_BINARY) + " " + args + " >" +
                                (dir() / (tag + ".txt")).string() + " 2>" +
                                (dir() / (tag + ".err")).string();
        const int st = std::system(cmd.c_str());
        return WIFEXITED(st) ? WEXITSTATUS(st) : -1;
    }
    // Renders a suite once per test run (at its own seed unless `seed` is given).
    static fs::path scene(const std::string& scenario, const std::string& extra = "") {
        std::string name = fs::path(scenario).stem().string() + extra;
        for (char& ch : name)
            if (ch == ' ' || ch == '-') ch = '_';
        fs::path out = dir() / name;
        if (!fs::exists(out / "truth.jsonl")) {
            fs::create_directories(dir());
            const int rc = run("scene --scenario " + kRoot + "/board/sim/scenarios/" + scenario +
                                   " --out " + out.string() + " " + extra,
                               "scene");
            EXPECT_EQ(rc, 0) << slurp(dir() / "scene.err");
        }
        return out;
    }
    static void TearDownTestSuite() { fs::remove_all(dir()); }

    // Per-gesture share of tip regions classified right by the shipped model.
    static std::array<double, vision::kGestureLabelCount> accuracy(
        const std::vector<fs::path>& scenes) {
        vision::ToolLikelihood tool_model;
        vision::GestureClassifier classifier;
        std::string error;
        EXPECT_TRUE(tool_model.load(kModels + "gesture_tool_likelihood.bin", error)) << error;
        EXPECT_TRUE(classifier.load(kModels + "gestures.yml", error)) << error;
        vision::GestureSegmenter segmenter(&tool_model, classifier.segmenter_params());
        std::vector<vision::GestureSample> samples;
        firmware::GestureDatasetStats stats;
        for (const fs::path& s : scenes)
            EXPECT_TRUE(
                firmware::add_gesture_samples(s.string(), segmenter, 1, samples, stats, error))
                << error;
        std::array<int, vision::kGestureLabelCount> total{}, right{};
        for (const auto& s : samples) {
            ++total[s.label];
            right[s.label] += classifier.classify(s.features).label == s.label;
        }
        std::array<double, vision::kGestureLabelCount> rate{};
        for (int c = 0; c < vision::kGestureLabelCount; ++c)
            rate[c] = total[c] ? double(right[c]) / total[c] : -1.0;
        return rate;
    }
};

}  // namespace

TEST_F(Gestures, ShippedModelMeetsTheSingleToolGoalOnHeldOutSuites) {
    // The seven orientations of fig. 3.22 for both tools, and fig. 3.12e-h (two
    // separate tools = two single-tool calls), at the suites' own seeds.
    const auto rate =
        accuracy({scene("fig322_grasper_orientations.yaml"),
                  scene("fig322_scissors_orientations.yaml"), scene("fig312_nonoverlapping.yaml")});
    // The goal: every single-tool gesture >= 95 %. (The two-tool gestures do
    // not meet theirs yet: docs/gestures.md.)
    for (int c = 0; c < 4; ++c) EXPECT_GE(rate[c], 0.95) << vision::kGestureLabels[c];
}

// The line `train-gestures` printed for one --test recording ("test DIR: ...").
std::string test_line(const std::string& printed, const fs::path& recording) {
    const std::size_t at = printed.find("test " + recording.string() + ":");
    return at == std::string::npos ? "" : printed.substr(at, printed.find('\n', at) - at);
}

TEST_F(Gestures, TrainGesturesWritesAModelThatLoadsAndRefusesBadInput) {
    const fs::path train = scene("fig322_grasper_orientations.yaml", "--seed 77");
    const fs::path model = dir() / "m.yml";
    ASSERT_EQ(run("train-gestures --scene " + train.string() + " --tool-model " + kModels +
                  "tool_likelihood.bin --iterations 200 --features book --out " + model.string() +
                  " --test " + train.string()),
              0)
        << slurp(dir() / "out.err");
    // --model measures the written model: the same line as the training run's --test.
    const std::string trained = test_line(slurp(dir() / "out.txt"), train);
    EXPECT_NE(trained.find("open_grasper "), std::string::npos) << trained;
    const auto written = fs::last_write_time(model);
    ASSERT_EQ(run("train-gestures --model " + model.string() + " --tool-model " + kModels +
                  "tool_likelihood.bin --test " + train.string()),
              0)
        << slurp(dir() / "out.err");
    EXPECT_EQ(test_line(slurp(dir() / "out.txt"), train), trained);
    EXPECT_EQ(fs::last_write_time(model), written);
    EXPECT_EQ(run("train-gestures --model " + model.string() + " --scene " + train.string() +
                  " --test " + train.string()),
              2);
    EXPECT_NE(slurp(dir() / "out.err").find("--model measures a model"), std::string::npos);
    EXPECT_EQ(run("train-gestures --model " + (dir() / "absent.yml").string() + " --test " +
                  train.string()),
              2);
    EXPECT_NE(slurp(dir() / "out.err").find("absent.yml"), std::string::npos);
    // The model segments with the threshold it was trained with (128 here, the default).
    EXPECT_EQ(run("train-gestures --model " + model.string() + " --threshold 170 --tool-model " +
                  kModels + "tool_likelihood.bin --test " + train.string()),
              2);
    EXPECT_NE(slurp(dir() / "out.err")
                  .find("--threshold 170: the model " + model.string() +
                        " was trained with threshold 128"),
              std::string::npos)
        << slurp(dir() / "out.err");
    EXPECT_EQ(run("train-gestures --scene " + train.string() + " --threshold 256 --out " +
                  model.string() + " --tool-model " + kModels + "tool_likelihood.bin"),
              2);
    EXPECT_NE(
        slurp(dir() / "out.err").find("--threshold needs a whole number in 1..255, got '256'"),
        std::string::npos);
    // The one-tool mask: above the mask threshold, and a model's own when measuring it.
    EXPECT_EQ(run("train-gestures --scene " + train.string() + " --threshold 170 " +
                  "--single-threshold 170 --out " + model.string() + " --tool-model " + kModels +
                  "tool_likelihood.bin"),
              2);
    EXPECT_NE(slurp(dir() / "out.err")
                  .find("--single-threshold 170 must be above the mask threshold 170"),
              std::string::npos)
        << slurp(dir() / "out.err");
    EXPECT_EQ(run("train-gestures --model " + model.string() + " --single-threshold 190 " +
                  "--tool-model " + kModels + "tool_likelihood.bin --test " + train.string()),
              2);
    EXPECT_NE(slurp(dir() / "out.err")
                  .find("--single-threshold 190: the model " + model.string() +
                        " was trained with no single-tool threshold"),
              std::string::npos)
        << slurp(dir() / "out.err");
    EXPECT_EQ(run("train-gestures --scene " + train.string() + " --segmentation morphology " +
                  "--single-threshold 190 --out " + model.string()),
              2);
    EXPECT_NE(slurp(dir() / "out.err").find("--single-threshold is for likelihood segmentation"),
              std::string::npos)
        << slurp(dir() / "out.err");
    vision::GestureClassifier c;
    std::string error;
    ASSERT_TRUE(c.load(model.string(), error)) << error;
    EXPECT_EQ(c.features(), vision::GestureFeatureSet::kBook);
    EXPECT_EQ(run("train-gestures --scene " + (dir() / "nowhere").string() + " --out " +
                  model.string() + " --tool-model " + kModels + "tool_likelihood.bin"),
              2);
    EXPECT_NE(slurp(dir() / "out.err").find("nowhere: no frames/ folder"), std::string::npos);
    EXPECT_EQ(
        run("train-gestures --scene " + train.string() + " --features six --out " + model.string()),
        2);
    EXPECT_NE(
        slurp(dir() / "out.err").find("--features: expected book, extended, topology or profile"),
        std::string::npos);
}

TEST_F(Gestures, AnOpenTenMillimetreGrasperIsLabelledByItsWidth) {
    // An open 10 mm grasper at a roll (test_varied_single_grasper's first pose): the
    // segmenter's tip is the farther jaw's end, 58 px from the truth's tip between the
    // jaws, past 0.08 x 640 = 51.2 px but within twice the tool's width (67 px). Before
    // the width rule such regions went unlabelled and no network learnt them.
    fs::create_directories(dir());
    const fs::path yaml = dir() / "open10.yaml", rec = dir() / "open10";
    std::ofstream(yaml) << "name: open10\ndescription: a 10 mm grasper open, then closed\n"
                           "frames: 2\ntools:\n  - diameter_mm: 10\n    tip: grasper\n"
                           "    jaw: open\n    pivot_mm: [77.8, 77.8, 15]\n"
                           "    start: {tip_mm: [-13.3, 4.8, 70.6]}\n    motion:\n"
                           "      - {move: [-13.3, 4.8, 70.6], frames: 0, roll_deg: -32.8}\n"
                           "      - {dwell: 1}\n      - {dwell: 1, jaw: closed}\n";
    ASSERT_EQ(run("scene --scenario " + yaml.string() + " --out " + rec.string(), "scene"), 0)
        << slurp(dir() / "scene.err");
    vision::ToolLikelihood tool_model;
    std::string error;
    ASSERT_TRUE(tool_model.load(kModels + "gesture_tool_likelihood.bin", error)) << error;
    vision::GestureSegmenterParams p;
    p.profile = true;
    vision::GestureSegmenter segmenter(&tool_model, p);
    std::vector<vision::GestureSample> samples;
    firmware::GestureDatasetStats stats;
    ASSERT_TRUE(firmware::add_gesture_samples(rec.string(), segmenter, 1, samples, stats, error))
        << error;
    EXPECT_EQ(stats.frames, 2);
    EXPECT_EQ(stats.unlabelled, 0);
    ASSERT_EQ(samples.size(), 2U);
    EXPECT_EQ(samples[0].label, vision::gesture_label_index("open_grasper"));
    EXPECT_EQ(samples[1].label, vision::gesture_label_index("closed_grasper"));
    // The case the rule is for: the open jaws' region tip lies past the fixed distance.
    cv::Mat img = cv::imread((rec / "frames" / "000000.png").string(), cv::IMREAD_COLOR);
    ASSERT_FALSE(img.empty());
    hal::Frame f;
    f.format = {img.cols, img.rows, static_cast<int>(img.step), hal::PixelFormat::kBgr24};
    f.data = img.data;
    segmenter.configure(f.format);
    std::array<vision::GestureBlob, vision::GestureSegmenter::kMaxBlobs> blobs{};
    ASSERT_EQ(segmenter.segment(f, blobs), 1U);
    std::vector<eval::TruthFrame> truth;
    ASSERT_TRUE(eval::read_truth((rec / "truth.jsonl").string(), truth, error)) << error;
    const auto& tool = truth[0].tools[0];
    const double d = std::hypot(blobs[0].tip.x - tool.tip_px.x, blobs[0].tip.y - tool.tip_px.y);
    EXPECT_GT(d, 0.08 * img.cols);
    EXPECT_LT(d, 2 * tool.width_px);
}

namespace {

fs::path board(const fs::path& dir, const std::string& model, double hold_ms,
               const std::string& pixel_model = kModels + "gesture_tool_likelihood.bin") {
    fs::path b = dir / ("board_" + std::to_string(static_cast<int>(hold_ms)) + ".yaml");
    std::ofstream(b) << "board: test\nanalysis:\n  stage: none\n  tracker: none\n  tool_model: "
                     << kModels << "tool_likelihood.bin\n  gestures: {model: " << model
                     << ", tool_model: " << pixel_model << ", hold_ms: " << hold_ms
                     << "}\nsim:\n  events: " << kRoot << "/board/sim/events.txt\n";
    return b;
}

}  // namespace

TEST_F(Gestures, CorruptModelDisablesGesturesNotTheVideo) {
    const fs::path rec = scene("fig322_grasper_orientations.yaml");
    std::string bytes = slurp(kModels + "gestures.yml");
    ASSERT_FALSE(bytes.empty());
    bytes[bytes.size() / 2] ^= 0x04;
    std::ofstream(dir() / "corrupt.yml") << bytes;
    const fs::path trace = dir() / "corrupt_trace.jsonl";
    ASSERT_EQ(run("sim --board " + board(dir(), (dir() / "corrupt.yml").string(), 1000).string() +
                  " --input " + (rec / "frames").string() + " --trace " + trace.string() +
                  " --out " + (dir() / "c.mkv").string()),
              0)
        << slurp(dir() / "out.err");
    const std::string err = slurp(dir() / "out.err");
    EXPECT_NE(err.find("corrupt.yml: checksum mismatch"), std::string::npos) << err;
    EXPECT_NE(err.find("gesture recognition disabled"), std::string::npos) << err;
    const std::string t = slurp(trace);
    EXPECT_EQ(t.find("\"gesture\""), std::string::npos);
    EXPECT_NE(slurp(dir() / "out.txt").find("28 frames in, 28 out"), std::string::npos)
        << slurp(dir() / "out.txt");
}

TEST_F(Gestures, CorruptPixelModelDisablesGesturesNotTheVideo) {
    // analysis.gestures.tool_model, the segmenter's own model: one flipped bit.
    const fs::path rec = scene("fig322_grasper_orientations.yaml");
    std::string bytes = slurp(kModels + "gesture_tool_likelihood.bin");
    ASSERT_FALSE(bytes.empty());
    bytes[bytes.size() / 2] ^= 0x10;
    std::ofstream(dir() / "corrupt_px.bin", std::ios::binary) << bytes;
    const fs::path trace = dir() / "corrupt_px_trace.jsonl";
    const fs::path b =
        board(dir(), kModels + "gestures.yml", 1000, (dir() / "corrupt_px.bin").string());
    ASSERT_EQ(run("sim --board " + b.string() + " --input " + (rec / "frames").string() +
                  " --trace " + trace.string() + " --out " + (dir() / "c.mkv").string()),
              0)
        << slurp(dir() / "out.err");
    const std::string err = slurp(dir() / "out.err");
    EXPECT_NE(err.find("needs analysis.gestures.tool_model: "), std::string::npos) << err;
    EXPECT_NE(err.find("corrupt_px.bin"), std::string::npos) << err;
    EXPECT_NE(err.find("gesture recognition disabled"), std::string::npos) << err;
    EXPECT_EQ(slurp(trace).find("\"gesture\""), std::string::npos);
    EXPECT_NE(slurp(dir() / "out.txt").find("28 frames in, 28 out"), std::string::npos)
        << slurp(dir() / "out.txt");
}

// The firmware segments with the threshold stored in the model: `sim`'s traced regions
// (count and tips, every frame, and each region's "read": the network's label and
// confidence on its features) are those of the segmenter run here at that threshold,
// for the shipped networks stored once with threshold 128 and once with 200 (which
// give different regions here: checked, so the comparison can tell them apart), and with
// the two masks 170 and 190 (one tool read on the second: GestureSegmenterParams).
TEST_F(Gestures, TheFirmwareSegmentsWithTheModelsThreshold) {
    const fs::path rec = scene("fig322_grasper_orientations.yaml");
    const std::string shipped = slurp(kModels + "gestures.yml");
    const std::size_t line = shipped.find("segmentation likelihood");
    ASSERT_NE(line, std::string::npos);
    const std::string third = shipped.substr(line, shipped.find('\n', line) - line);
    vision::ToolLikelihood pixels;
    std::string error;
    ASSERT_TRUE(pixels.load(kModels + "gesture_tool_likelihood.bin", error)) << error;
    std::vector<std::vector<std::array<double, 2>>> tips_at[3];
    int overruled = 0, read_any = 0;  // regions read as a gesture: all, and set to none
    const struct { int threshold, single; } masks[] = {{128, 0}, {200, 0}, {170, 190}};
    for (std::size_t m = 0; m < std::size(masks); ++m) {
        const int threshold = masks[m].threshold, single = masks[m].single;
        const std::string name = "t" + std::to_string(threshold);
        const fs::path model = dir() / (name + ".yml");
        std::string line3 = "segmentation likelihood";
        if (threshold != 128) line3 += " threshold " + std::to_string(threshold);
        if (single != 0) line3 += " single " + std::to_string(single);
        std::ofstream(model) << test::edited_gesture_model(shipped, third, line3);
        vision::GestureClassifier classifier;
        ASSERT_TRUE(classifier.load(model.string(), error)) << error;
        ASSERT_EQ(classifier.segmentation_threshold(), threshold);
        ASSERT_EQ(classifier.segmenter_params().threshold, threshold);
        ASSERT_EQ(classifier.segmenter_params().single_threshold, single);
        const fs::path trace = dir() / (name + "_trace.jsonl");
        const fs::path b = dir() / ("board_" + name);
        fs::create_directories(b);
        ASSERT_EQ(run("sim --board " + board(b, model.string(), 1000).string() + " --input " +
                      (rec / "frames").string() + " --trace " + trace.string() + " --out " +
                      (dir() / (name + ".mkv")).string()),
                  0)
            << slurp(dir() / "out.err");
        vision::GestureSegmenter segmenter(&pixels, classifier.segmenter_params());
        std::ifstream lines(trace);
        std::string l;
        auto& tips = tips_at[m];
        for (int frame = 0; std::getline(lines, l); ++frame) {
            char png[32];
            std::snprintf(png, sizeof png, "%06d.png", frame);
            cv::Mat img = cv::imread((rec / "frames" / png).string(), cv::IMREAD_COLOR);
            ASSERT_FALSE(img.empty()) << png;
            hal::Frame f;
            f.format = {img.cols, img.rows, static_cast<int>(img.step), hal::PixelFormat::kBgr24};
            f.data = img.data;
            if (frame == 0) segmenter.configure(f.format);
            std::array<vision::GestureBlob, vision::GestureSegmenter::kMaxBlobs> blobs{};
            const std::size_t n = segmenter.segment(f, blobs);
            tips.emplace_back();
            const nlohmann::json traced = nlohmann::json::parse(l).at("gesture").at("tools");
            ASSERT_EQ(traced.size(), n) << name << " frame " << frame;
            for (std::size_t i = 0; i < n; ++i) {
                tips.back().push_back({blobs[i].tip.x, blobs[i].tip.y});
                const nlohmann::json& tip = traced[i].at("tip_px");
                EXPECT_NEAR(tip.at(0).get<double>(), blobs[i].tip.x, 1e-6)
                    << name << " frame " << frame;
                EXPECT_NEAR(tip.at(1).get<double>(), blobs[i].tip.y, 1e-6)
                    << name << " frame " << frame;
                // "read": the network's label before the stage's rules, its confidence;
                // "label": that or null.
                const vision::GestureResult r =
                    classifier.classify(blobs[i].features, blobs[i].entries);
                const nlohmann::json& got = traced[i].at("read");
                if (r.label >= 0)
                    EXPECT_EQ(got, vision::kGestureLabels[r.label]) << name << " frame " << frame;
                else
                    EXPECT_TRUE(got.is_null()) << name << " frame " << frame;
                EXPECT_NEAR(traced[i].at("confidence").get<double>(), r.confidence, 1e-6);
                const nlohmann::json& label = traced[i].at("label");
                EXPECT_TRUE(label.is_null() || label == got) << name << " frame " << frame;
                overruled += !got.is_null() && label.is_null();
                read_any += !got.is_null();
            }
        }
        EXPECT_EQ(tips.size(), 28u);
    }
    EXPECT_NE(tips_at[0], tips_at[1]);
    EXPECT_NE(tips_at[2], tips_at[0]);
    EXPECT_NE(tips_at[2], tips_at[1]);
    std::printf("regions read as a gesture: %d, set to none by the stage's rules: %d\n", read_any,
                overruled);
    EXPECT_GT(read_any, 60);
}

TEST_F(Gestures, EvalConfusionOnARenderedSuite) {
    // Ten frames per state (the book's ten trials) and a hold of 120 ms (3 frames).
    const fs::path rec = scene("fig322_grasper_orientations.yaml", "--scale 5");
    const fs::path trace = dir() / "g_trace.jsonl";
    ASSERT_EQ(run("sim --board " + board(dir(), kModels + "gestures.yml", 120).string() +
                  " --input " + (rec / "frames").string() + " --trace " + trace.string() +
                  " --out " + (dir() / "g.mkv").string()),
              0)
        << slurp(dir() / "out.err");
    const int rc = run("eval --trace " + trace.string() + " --truth " +
                       (rec / "truth.jsonl").string() + " --min-gesture-rate 0.95");
    const std::string out = slurp(dir() / "out.txt");
    EXPECT_EQ(rc, 0) << out << slurp(dir() / "out.err");
    // Seven orientations x (open, closed) = 14 trials; the rate threshold is the goal.
    EXPECT_NE(out.find("gestures: 14 trials"), std::string::npos) << out;
}
