// endotower train-gestures: trains the tool-gesture classifier (book ch. 3) from
// labelled recordings and writes the model file atomically; --test scores it on
// held-out recordings (per tip region, before the hold-still rule); --model scores a
// model file that exists instead of training one.
#include <cstdio>
#include <cstdlib>

#include "commands.hpp"
#include "endotower/system/syscall.hpp"
#include "gesture_dataset.hpp"

namespace endotower::firmware {

namespace {

void print_help() {
    std::printf(
        "usage: endotower train-gestures --scene DIR... [--test DIR]... --out FILE\n"
        "                                [--features book|extended|topology|profile]\n"
        "                                [--segmentation "
        "likelihood|morphology]\n"
        "                                [--threshold N] [--single-threshold M]\n"
        "                                [--tool-model FILE] [--every N]\n"
        "                                [--hidden N] "
        "[--iterations N]\n"
        "                                [--networks one|two] [--rprop] [--match-widths N]\n"
        "                                [--two-tool-only-from MODEL]\n"
        "       endotower train-gestures --model FILE --test DIR... [--tool-model FILE]\n\n"
        "Trains the gesture network (docs/gestures.md) on the tip regions of labelled\n"
        "recordings and writes the model file atomically; with --model, measures a\n"
        "model file on the --test recordings instead (nothing is trained or written).\n\n"
        "  --scene DIR        training recording: DIR/frames/*.png and DIR/truth.jsonl (the "
        "output\n"
        "                     of 'endotower scene', or a hand-labelled clip in that layout)\n"
        "  --test DIR         held-out recording: prints the per-gesture accuracy on its tips\n"
        "                     and the wrong calls (truth->call count; none = no gesture)\n"
        "  --features F       book: the six features, 6-20-7 (the book's baseline);\n"
        "                     extended: nine and a 'not a tool' class, 9-20-8;\n"
        "                     topology: those nine and the two largest holes, 11-20-8\n"
        "                     (default); profile: a topology model and a 31-20-8 network\n"
        "                     on those eleven and the width and runs across the shaft at\n"
        "                     10 stations back from the tip, averaged for single tools\n"
        "  --segmentation S   likelihood (default) or morphology (eq. 3.3-3.5)\n"
        "  --threshold N      likelihood segmentation: the mask threshold on the smoothed tool\n"
        "                     probability, 1..255 (default 128 = even odds; stored in the\n"
        "                     model, so the firmware segments the same way)\n"
        "  --single-threshold M  likelihood: a second mask at M (above the threshold) on\n"
        "                     which a region that enters once (one tool) is measured\n"
        "                     (default 0: none; stored in the model)\n"
        "  --tool-model FILE  the tool likelihood model (needed for likelihood segmentation)\n"
        "  --every N          use every N-th frame (default 1)\n"
        "  --hidden N         hidden units (default 20)\n"
        "  --iterations N     backpropagation epochs (default 3000)\n"
        "  --networks N       one (default): one network for every region; two (not book):\n"
        "                     one for single tools, one for two-tool regions (cross, triangle,\n"
        "                     double triangle, where the segmenter sees two entries);\n"
        "                     both learn from the --scene recordings, the single-tool one\n"
        "                     also from the --single-tool-scene ones, the two-tool one\n"
        "                     also from the --two-tool-scene ones\n"
        "  --single-tool-scene DIR  a recording for the single-tool network only (two)\n"
        "  --two-tool-scene DIR     a recording for the two-tool network only (two)\n"
        "  --out FILE         the model file (e.g. board/sim/models/gestures.yml)\n"
        "  --model FILE       measure this model (its features and segmentation) on --test\n"
        "  --match-widths N   a training region takes the label of the tool whose tip is\n"
        "                     within 0.08 x the frame width or N x the tool's width of its\n"
        "                     tip (default 2; 0: the fraction alone); --test always 2\n"
        "  --rprop            train by RPROP (batch; the result does not depend on the\n"
        "                     order of the samples) instead of sequential backpropagation\n"
        "  --two-tool-only-from FILE  train only the two-tool network; the single-tool\n"
        "                     and profile networks are this model's, unchanged\n\n"
        "Exit status: 0 written (or measured), 1 could not train or write, 2 bad usage or\n"
        "input.\n");
}

int usage_error(const std::string& m) {
    std::fprintf(stderr, "endotower train-gestures: %s\n(see 'endotower train-gestures --help')\n",
                 m.c_str());
    return kExitBadInput;
}

bool whole(const std::string& v, long lo, long hi, long& out) {
    char* end = nullptr;
    out = std::strtol(v.c_str(), &end, 10);
    return !v.empty() && *end == 0 && out >= lo && out <= hi;
}

// Per held-out recording: the per-gesture accuracy on its tip regions and the wrong calls.
int print_tests(const vision::GestureClassifier& classifier, vision::GestureSegmenter& segmenter,
                const std::vector<std::string>& tests, std::string& error) {
    for (const std::string& d : tests) {
        std::vector<vision::GestureSample> held_out;
        GestureDatasetStats ts;
        if (!add_gesture_samples(d, segmenter, 1, held_out, ts, error, 0.08, true))
            return usage_error(error);
        constexpr int kClasses = vision::kGestureLabelCount + 1;  // the last: no gesture
        std::array<int, kClasses> total{}, right{};
        std::array<std::array<int, kClasses>, kClasses> called{};  // [truth][call]
        for (const auto& s : held_out) {
            ++total[s.label];
            const int got = classifier.classify(s.features, s.entries).label;
            if (got == s.label || (got < 0 && s.label == vision::kNotATool)) ++right[s.label];
            ++called[s.label][got < 0 ? vision::kNotATool : got];
        }
        std::printf("test %s:", d.c_str());
        for (int c = 0; c < vision::kGestureLabelCount; ++c)
            if (total[c] > 0)
                std::printf(" %s %d/%d", vision::kGestureLabels[c], right[c], total[c]);
        std::printf(" | tissue rejected %d/%d", right[vision::kNotATool], total[vision::kNotATool]);
        const char* sep = " | wrong:";
        for (int t = 0; t < kClasses; ++t)
            for (int c = 0; c < kClasses; ++c)
                if (c != t && called[t][c] > 0) {
                    auto name = [](int k) {
                        return k == vision::kNotATool ? "none" : vision::kGestureLabels[k];
                    };
                    std::printf("%s %s->%s %d", sep, name(t), name(c), called[t][c]);
                    sep = ",";
                }
        std::printf("\n");
    }
    return kExitOk;
}

}  // namespace

int run_train_gestures_command(const Args& args) {
    std::vector<std::string> scenes, single_scenes, two_scenes, tests;
    std::string out, tool_model_path, model_path, base_path;
    vision::GestureTrainParams params;
    params.features = vision::GestureFeatureSet::kTopology;
    long every = 1, hidden = 20, iterations = 3000, match_widths = 2, threshold = 0,
         single_threshold = -1;
    for (std::size_t i = 0; i < args.size(); ++i) {
        const std::string& k = args[i];
        if (k == "--help" || k == "-h") {
            print_help();
            return kExitOk;
        }
        if (k == "--rprop") {
            params.rprop = true;
            continue;
        }
        if (i + 1 >= args.size()) return usage_error("option " + k + " needs a value");
        const std::string& v = args[++i];
        if (k == "--scene")
            scenes.push_back(v);
        else if (k == "--single-tool-scene")
            single_scenes.push_back(v);
        else if (k == "--two-tool-scene")
            two_scenes.push_back(v);
        else if (k == "--test")
            tests.push_back(v);
        else if (k == "--out")
            out = v;
        else if (k == "--model")
            model_path = v;
        else if (k == "--two-tool-only-from")
            base_path = v;
        else if (k == "--tool-model")
            tool_model_path = v;
        else if (k == "--features") {
            if (v != "book" && v != "extended" && v != "topology" && v != "profile")
                return usage_error(
                    "--features: expected book, extended, topology or profile, got '" + v + "'");
            params.features = v == "book"       ? vision::GestureFeatureSet::kBook
                              : v == "extended" ? vision::GestureFeatureSet::kExtended
                              : v == "topology" ? vision::GestureFeatureSet::kTopology
                                                : vision::GestureFeatureSet::kProfile;
        } else if (k == "--segmentation") {
            if (v != "likelihood" && v != "morphology")
                return usage_error("--segmentation: expected likelihood or morphology, got '" + v +
                                   "'");
            params.segmentation = v == "morphology" ? vision::GestureSegmentation::kMorphology
                                                    : vision::GestureSegmentation::kLikelihood;
        } else if (k == "--threshold") {
            if (!whole(v, 1, 255, threshold))
                return usage_error("--threshold needs a whole number in 1..255, got '" + v + "'");
        } else if (k == "--single-threshold") {
            if (!whole(v, 0, 255, single_threshold))
                return usage_error("--single-threshold needs a whole number in 0..255, got '" + v +
                                   "'");
        } else if (k == "--every") {
            if (!whole(v, 1, 100000, every))
                return usage_error("--every needs a whole number >= 1, got '" + v + "'");
        } else if (k == "--hidden") {
            if (!whole(v, 2, vision::kGestureMaxHidden, hidden))
                return usage_error("--hidden needs a whole number in 2.." +
                                   std::to_string(vision::kGestureMaxHidden) + ", got '" + v + "'");
        } else if (k == "--networks") {
            if (v != "one" && v != "two")
                return usage_error("--networks: expected one or two, got '" + v + "'");
            params.two_tool_network = v == "two";
        } else if (k == "--match-widths") {
            if (!whole(v, 0, 100, match_widths))
                return usage_error("--match-widths needs a whole number 0..100, got '" + v + "'");
        } else if (k == "--iterations") {
            if (!whole(v, 1, 1000000, iterations))
                return usage_error("--iterations needs a whole number >= 1, got '" + v + "'");
        } else
            return usage_error("unknown option '" + k + "'");
    }
    vision::GestureClassifier classifier;
    std::string error;
    // A model measured or extended: its features and segmentation are the ones used.
    auto take_model = [&params](const vision::GestureClassifier& c) {
        params.features = c.features();
        params.segmentation = c.segmentation();
        params.threshold = c.segmentation_threshold();
        params.single_threshold = c.single_tool_threshold();
    };
    if (!model_path.empty()) {
        // Measure a model that exists (the shipped one) on the --test recordings, no training.
        if (!scenes.empty() || !single_scenes.empty() || !two_scenes.empty() || !out.empty())
            return usage_error("--model measures a model: give only --test DIR and --tool-model");
        if (tests.empty()) return usage_error("--model needs at least one --test DIR");
        if (!classifier.load(model_path, error)) return usage_error(error);
        take_model(classifier);
    } else {
        if (out.empty()) return usage_error("give --out FILE");
        if (scenes.empty()) return usage_error("give at least one --scene DIR");
    }
    if (!base_path.empty()) {
        // Only the two-tool network is trained; the single-tool ones are the base's.
        if (!model_path.empty() || !single_scenes.empty())
            return usage_error(
                "--two-tool-only-from trains the two-tool network: no --model or "
                "--single-tool-scene");
        if (!classifier.load(base_path, error)) return usage_error(error);
        if (!classifier.has_two_tool_network())
            return usage_error(base_path + ": has no two-tool network (--networks two)");
        take_model(classifier);
        params.two_tool_network = true;
    }
    // A model segments with the threshold it was trained with: one given must agree.
    if (threshold != 0) {
        if (params.segmentation != vision::GestureSegmentation::kLikelihood)
            return usage_error("--threshold is for likelihood segmentation");
        if ((!model_path.empty() || !base_path.empty()) && threshold != params.threshold)
            return usage_error("--threshold " + std::to_string(threshold) + ": the model " +
                               (model_path.empty() ? base_path : model_path) +
                               " was trained with threshold " + std::to_string(params.threshold));
        params.threshold = static_cast<int>(threshold);
    }
    if (single_threshold >= 0) {
        if (params.segmentation != vision::GestureSegmentation::kLikelihood)
            return usage_error("--single-threshold is for likelihood segmentation");
        if ((!model_path.empty() || !base_path.empty()) &&
            single_threshold != params.single_threshold)
            return usage_error(
                "--single-threshold " + std::to_string(single_threshold) + ": the model " +
                (model_path.empty() ? base_path : model_path) + " was trained with " +
                (params.single_threshold == 0
                     ? std::string("no single-tool threshold")
                     : "single-tool threshold " + std::to_string(params.single_threshold)));
        if (single_threshold != 0 && single_threshold <= params.threshold)
            return usage_error("--single-threshold " + std::to_string(single_threshold) +
                               " must be above the mask threshold " +
                               std::to_string(params.threshold));
        params.single_threshold = static_cast<int>(single_threshold);
    }
    params.hidden = static_cast<int>(hidden);
    params.iterations = static_cast<int>(iterations);
    vision::ToolLikelihood tool_model;
    if (params.segmentation == vision::GestureSegmentation::kLikelihood) {
        if (tool_model_path.empty())
            return usage_error("likelihood segmentation needs --tool-model FILE");
        if (!tool_model.load(tool_model_path, error)) return usage_error(error);
    }
    vision::GestureSegmenter segmenter(&tool_model, vision::gesture_segmenter_params(params));

    if (!model_path.empty()) return print_tests(classifier, segmenter, tests, error);
    std::vector<vision::GestureSample> samples;
    GestureDatasetStats stats;
    for (const std::string& d : scenes)
        if (!add_gesture_samples(d, segmenter, static_cast<int>(every), samples, stats, error, 0.08,
                                 params.features != vision::GestureFeatureSet::kBook,
                                 static_cast<double>(match_widths)))
            return usage_error(error);
    if (!single_scenes.empty() && !params.two_tool_network)
        return usage_error("--single-tool-scene needs --networks two");
    if (!two_scenes.empty() && !params.two_tool_network)
        return usage_error("--two-tool-scene needs --networks two");
    for (const bool single : {true, false})
        for (const std::string& d : single ? single_scenes : two_scenes) {
            const std::size_t from = samples.size();
            if (!add_gesture_samples(d, segmenter, static_cast<int>(every), samples, stats, error,
                                     0.08, true, static_cast<double>(match_widths)))
                return usage_error(error);
            for (std::size_t i = from; i < samples.size(); ++i)
                (single ? samples[i].single_tool_only : samples[i].two_tool_only) = true;
        }
    std::array<int, vision::kGestureLabelCount + 1> per_class{};
    for (const auto& s : samples) ++per_class[s.label];
    std::printf("train-gestures: %d frames, %d tip regions, %d unlabelled, %zu samples:",
                stats.frames, stats.blobs, stats.unlabelled, samples.size());
    for (int c = 0; c < vision::kGestureLabelCount; ++c)
        std::printf(" %s %d", vision::kGestureLabels[c], per_class[c]);
    std::printf(" not_a_tool %d\n", per_class[vision::kNotATool]);
    if (!(base_path.empty() ? classifier.train(samples, params, error)
                            : classifier.retrain_two_tool(samples, params, error))) {
        std::fprintf(stderr, "endotower train-gestures: %s\n", error.c_str());
        return kExitFailure;
    }
    if (const int rc = print_tests(classifier, segmenter, tests, error); rc != kExitOk) return rc;
    if (!system::write_file_atomic(out, classifier.serialise(), error)) {
        std::fprintf(stderr, "endotower train-gestures: %s\n", error.c_str());
        return kExitFailure;
    }
    std::printf("train-gestures: -> %s\n", out.c_str());
    return kExitOk;
}

}  // namespace endotower::firmware
