#include "endotower/vision/gesture_classifier.hpp"

#include <algorithm>
#include <cfloat>
#include <cinttypes>
#include <cstdio>
#include <fstream>
#include <opencv2/core.hpp>
#include <opencv2/ml.hpp>
#include <sstream>

namespace endotower::vision {

namespace {

constexpr const char* kMagic = "ETGES1\n";
constexpr const char* kNode = "opencv_ml_ann_mlp";
constexpr const char* kTwoToolNode = "two_tool_ann_mlp";
constexpr const char* kProfileNode = "profile_ann_mlp";
constexpr int kDefaultThreshold = GestureSegmenterParams{}.threshold;  // even odds

std::uint64_t fnv1a(const char* p, std::size_t n) {
    std::uint64_t h = 1469598103934665603ull;
    for (std::size_t i = 0; i < n; ++i)
        h = (h ^ static_cast<std::uint8_t>(p[i])) * 1099511628211ull;
    return h;
}

const char* feature_name(GestureFeatureSet s) {
    return s == GestureFeatureSet::kBook       ? "book"
           : s == GestureFeatureSet::kExtended ? "extended"
           : s == GestureFeatureSet::kTopology ? "topology"
                                               : "profile";
}
const char* segmentation_name(GestureSegmentation s) {
    return s == GestureSegmentation::kMorphology ? "morphology" : "likelihood";
}

// OpenCV's ANN_MLP::read trusts the file: it sizes the weights from layer_sizes and
// reads as many numbers as each list holds, leaving the rest uninitialised. So the
// shape is checked first: nf-h-classes layers, 2 to kGestureMaxHidden hidden neurons
// (what the trainer accepts), and every list exactly as long as the layers make it.
// Returns what is wrong, or "" when the node is nf-h-classes throughout.
std::string network_shape_error(const cv::FileNode& net, int nf, int classes) {
    const cv::FileNode sizes = net["layer_sizes"];
    if (!sizes.isSeq() || sizes.size() != 3 || !sizes[0].isInt() || !sizes[1].isInt() ||
        !sizes[2].isInt())
        return "layer_sizes is not a list of three integers";
    const int in = static_cast<int>(sizes[0]), hidden = static_cast<int>(sizes[1]),
              out = static_cast<int>(sizes[2]);
    if (in != nf || out != classes || hidden < 2 || hidden > kGestureMaxHidden)
        return "layer_sizes is " + std::to_string(in) + "-" + std::to_string(hidden) + "-" +
               std::to_string(out);
    const std::pair<const char*, std::size_t> lists[] = {
        {"input_scale", 2 * static_cast<std::size_t>(nf)},
        {"output_scale", 2 * static_cast<std::size_t>(classes)},
        {"inv_output_scale", 2 * static_cast<std::size_t>(classes)}};
    auto wrong_length = [](const cv::FileNode& n, std::size_t want) {
        return !n.isSeq() || n.size() != want;
    };
    for (const auto& [key, want] : lists)
        if (wrong_length(net[key], want))
            return std::string(key) + " does not hold " + std::to_string(want) + " numbers";
    const cv::FileNode w = net["weights"];
    if (wrong_length(w, 2) ||
        wrong_length(w[0], static_cast<std::size_t>(nf + 1) * static_cast<std::size_t>(hidden)) ||
        wrong_length(w[1],
                     static_cast<std::size_t>(hidden + 1) * static_cast<std::size_t>(classes)))
        return "the weights are not two lists of " + std::to_string((nf + 1) * hidden) + " and " +
               std::to_string((hidden + 1) * classes) + " numbers";
    return {};
}

}  // namespace

int gesture_label_index(const std::string& label) {
    for (int i = 0; i < kGestureLabelCount; ++i)
        if (label == kGestureLabels[i]) return i;
    return -1;
}

struct GestureClassifier::Net {
    cv::Ptr<cv::ml::ANN_MLP> ann, two_tool;  // two_tool: empty for one network
    cv::Ptr<cv::ml::ANN_MLP> profile;        // the profile set's third network, else empty
    // Per-call buffers, sized once (classify() allocates nothing).
    mutable cv::Mat input = cv::Mat(1, GestureFeatures::kProfileCount, CV_32F),
                    output = cv::Mat(1, kGestureLabelCount + 1, CV_32F),
                    profile_output = cv::Mat(1, kGestureLabelCount + 1, CV_32F);
};

GestureClassifier::GestureClassifier() : net_(std::make_unique<Net>()) {}
GestureClassifier::~GestureClassifier() = default;

bool GestureClassifier::trained() const {
    return !net_->ann.empty() && net_->ann->isTrained();
}

bool GestureClassifier::has_two_tool_network() const {
    return !net_->two_tool.empty() && net_->two_tool->isTrained();
}

namespace {

// One network on the samples `take` accepts.
template <typename Take>
cv::Ptr<cv::ml::ANN_MLP> train_network(const std::vector<GestureSample>& samples, Take take,
                                       const GestureTrainParams& params, int nf, const char* what,
                                       std::string& error) {
    const bool book = params.features == GestureFeatureSet::kBook;
    const int classes = book ? kGestureLabelCount : kGestureLabelCount + 1;
    std::array<std::vector<const GestureSample*>, kGestureLabelCount + 1> by_class;
    for (const GestureSample& s : samples)
        if (s.features.valid && s.label >= 0 && s.label < classes && take(s))
            by_class[s.label].push_back(&s);
    std::size_t most = 0;
    for (const auto& c : by_class) most = std::max(most, c.size());
    if (most == 0) {
        error = std::string("no training samples") + what;
        return {};
    }
    // Equal weight per class: the rarer classes' samples are repeated in turn.
    cv::Mat x(0, nf, CV_32F), y(0, classes, CV_32F);
    for (const auto& c : by_class)
        for (std::size_t i = 0; !c.empty() && i < most; ++i) {
            const auto v = c[i % c.size()]->features.as_vector();
            cv::Mat row(1, nf, CV_32F);
            for (int k = 0; k < nf; ++k) row.at<float>(0, k) = v[k];
            x.push_back(row);
            cv::Mat t(1, classes, CV_32F, cv::Scalar(0.1f));
            t.at<float>(0, c[i % c.size()]->label) = 0.9f;
            y.push_back(t);
        }
    try {
        cv::theRNG().state = 0x12345678;  // ANN_MLP draws its initial weights from it
        cv::Ptr<cv::ml::ANN_MLP> ann = cv::ml::ANN_MLP::create();
        ann->setLayerSizes(cv::Mat_<int>({1, 3}, {nf, params.hidden, classes}));
        ann->setActivationFunction(cv::ml::ANN_MLP::SIGMOID_SYM, 0, 0);
        // RPROP (batch) learns the same network whatever the order of the samples; the
        // book's sequential backpropagation does not (docs/gestures.md, "Crossings from
        // every side").
        if (params.rprop)
            ann->setTrainMethod(cv::ml::ANN_MLP::RPROP, 0.1, FLT_EPSILON);
        else
            ann->setTrainMethod(cv::ml::ANN_MLP::BACKPROP, 0.05, 0.1);
        ann->setTermCriteria(cv::TermCriteria(cv::TermCriteria::MAX_ITER + cv::TermCriteria::EPS,
                                              params.iterations, 1e-7));
        if (!ann->train(cv::ml::TrainData::create(x, cv::ml::ROW_SAMPLE, y))) {
            error = std::string("backpropagation did not converge") + what;
            return {};
        }
        return ann;
    } catch (const cv::Exception& e) {
        error = "training failed" + std::string(what) + ": " + e.msg;
        return {};
    }
}

}  // namespace

bool GestureClassifier::train(const std::vector<GestureSample>& samples,
                              const GestureTrainParams& params, std::string& error) {
    if (params.two_tool_network && params.features == GestureFeatureSet::kBook) {
        error =
            "two networks need the extended, topology or profile features (the book's is one "
            "6-20-7)";
        return false;
    }
    const int nf = GestureFeatures::count(base_feature_set(params.features));
    const cv::Ptr<cv::ml::ANN_MLP> one = train_network(
        samples, [](const GestureSample& s) { return !s.two_tool_only; }, params, nf,
        params.two_tool_network ? " (single-tool network)" : "", error);
    if (one.empty()) return false;
    cv::Ptr<cv::ml::ANN_MLP> two, profile;
    if (params.two_tool_network) {
        two = train_network(
            samples, [](const GestureSample& s) { return !s.single_tool_only; }, params, nf,
            " (two-tool network)", error);
        if (two.empty()) return false;
    }
    if (params.features == GestureFeatureSet::kProfile) {
        profile = train_network(
            samples, [](const GestureSample& s) { return !s.two_tool_only; }, params,
            GestureFeatures::kProfileCount, " (profile network)", error);
        if (profile.empty()) return false;
    }
    net_->ann = one;
    net_->two_tool = two;
    net_->profile = profile;
    features_ = params.features;
    segmentation_ = params.segmentation;
    threshold_ = params.threshold;
    single_threshold_ = single_mask_threshold(params);
    return true;
}

bool GestureClassifier::retrain_two_tool(const std::vector<GestureSample>& samples,
                                         const GestureTrainParams& params, std::string& error) {
    if (!has_two_tool_network()) {
        error = "the model has no two-tool network to retrain";
        return false;
    }
    if (params.features != features_ || params.segmentation != segmentation_ ||
        params.threshold != threshold_ || single_mask_threshold(params) != single_threshold_) {
        error = "the samples' features or segmentation are not the model's";
        return false;
    }
    const cv::Ptr<cv::ml::ANN_MLP> two = train_network(
        samples, [](const GestureSample& s) { return !s.single_tool_only; }, params,
        GestureFeatures::count(base_feature_set(features_)), " (two-tool network)", error);
    if (two.empty()) return false;
    net_->two_tool = two;
    return true;
}

GestureResult GestureClassifier::run(bool two_tool_network, const GestureFeatures& f,
                                     bool one_tool) const {
    GestureResult r;
    const auto v = f.as_vector();
    auto predict = [&](const cv::ml::ANN_MLP& ann, int nf, cv::Mat& out) {
        cv::Mat in = net_->input.colRange(0, nf);
        for (int k = 0; k < nf; ++k) in.at<float>(0, k) = v[k];
        try {
            ann.predict(in, out);
        } catch (const cv::Exception&) {
            return false;
        }
        return true;
    };
    const int nf = GestureFeatures::count(base_feature_set(features_));
    if (!predict(two_tool_network ? *net_->two_tool : *net_->ann, nf, net_->output)) return r;
    if (!two_tool_network && !net_->profile.empty()) {
        // The profile set: the single-tool decision is the mean of the two networks'
        // outputs (the topology network reads the fixed orientations best, the
        // profile network the random ones; docs/gestures.md).
        if (!predict(*net_->profile, GestureFeatures::kProfileCount, net_->profile_output))
            return r;
        float* a = net_->output.ptr<float>(0);
        const float* b = net_->profile_output.ptr<float>(0);
        for (int k = 0; k < net_->output.cols; ++k) a[k] = 0.5f * (a[k] + b[k]);
    }
    const float* o = net_->output.ptr<float>(0);
    const int classes = net_->output.cols;
    int best = static_cast<int>(std::max_element(o, o + classes) - o);
    if (one_tool && two_tool_gesture(best)) {
        // One tool: the best of its own gestures and "not a tool".
        best = static_cast<int>(std::max_element(o, o + kSingleToolLabels) - o);
        if (classes > kGestureLabelCount && o[kNotATool] > o[best]) best = kNotATool;
    }
    r.confidence = std::clamp<double>(o[best], 0.0, 1.0);
    r.label = best < kGestureLabelCount ? best : -1;  // "not a tool": no gesture
    return r;
}

GestureResult GestureClassifier::classify(const GestureFeatures& f, int entries) const {
    if (!trained() || !f.valid) return {};
    if (!has_two_tool_network()) return run(false, f, false);
    // A region entering the picture once is one tool (both tools of a two-tool gesture
    // come in through the rim: every such training region has two entries).
    if (entries != 2) return run(false, f, true);
    // Two entries: two tools meeting, or one tool lying along the rim (the activation
    // pose at the bottom of the view). The two-tool network names the two-tool
    // gestures; where it sees none, the region is read as a single tool.
    const GestureResult two = run(true, f, false);
    if (two_tool_gesture(two.label)) return two;
    // Where the two networks disagree on whether two tools meet, no gesture: measured
    // better than the best single-tool reading (4 double triangles read as closed
    // scissors per region; docs/gestures.md).
    GestureResult one = run(false, f, false);
    if (two_tool_gesture(one.label)) one.label = -1;
    return one;
}

GestureSegmenterParams gesture_segmenter_params(const GestureTrainParams& p) {
    GestureSegmenterParams s;
    s.method = p.segmentation;
    s.threshold = p.threshold;
    s.single_threshold = single_mask_threshold(p);
    s.profile = p.features == GestureFeatureSet::kProfile;
    return s;
}

GestureSegmenterParams GestureClassifier::segmenter_params() const {
    GestureTrainParams p;
    p.features = features_;
    p.segmentation = segmentation_;
    p.threshold = threshold_;
    p.single_threshold = single_threshold_;
    return gesture_segmenter_params(p);
}

std::string GestureClassifier::serialise() const {
    std::string body = kMagic;
    body += std::string("features ") + feature_name(features_) + "\n";
    body += std::string("segmentation ") + segmentation_name(segmentation_);
    // The default threshold is not written: the files written before it existed read the same.
    if (segmentation_ == GestureSegmentation::kLikelihood &&
        (threshold_ != kDefaultThreshold || single_threshold_ != 0))
        body += " threshold " + std::to_string(threshold_);
    if (single_threshold_ != 0) body += " single " + std::to_string(single_threshold_);
    body += "\n";
    if (trained()) {
        cv::FileStorage fs(".yml", cv::FileStorage::WRITE | cv::FileStorage::MEMORY |
                                       cv::FileStorage::FORMAT_YAML);
        fs << kNode << "{";
        net_->ann->write(fs);
        fs << "}";
        if (has_two_tool_network()) {
            fs << kTwoToolNode << "{";
            net_->two_tool->write(fs);
            fs << "}";
        }
        if (!net_->profile.empty()) {
            fs << kProfileNode << "{";
            net_->profile->write(fs);
            fs << "}";
        }
        body += fs.releaseAndGetString();
        if (body.back() != '\n') body += '\n';
    }
    char tail[32];
    std::snprintf(tail, sizeof tail, "fnv1a %016" PRIx64 "\n", fnv1a(body.data(), body.size()));
    return body + tail;
}

bool GestureClassifier::parse(const std::string& bytes, const std::string& name,
                              std::string& error) {
    auto fail = [&](const std::string& what) {
        error = name + ": " + what;
        return false;
    };
    const std::string magic = kMagic;
    if (bytes.compare(0, magic.size(), magic) != 0)
        return fail("not a gesture model (expected the header ETGES1)");
    constexpr std::size_t kTail = 6 + 16 + 1;
    if (bytes.size() < magic.size() + kTail)
        return fail("truncated (no 'fnv1a' checksum line at the end)");
    const std::size_t body_size = bytes.size() - kTail;
    if (bytes.compare(body_size, 6, "fnv1a ") != 0 || bytes.back() != '\n')
        return fail("truncated (no 'fnv1a' checksum line at the end)");
    char want[17];
    std::snprintf(want, sizeof want, "%016" PRIx64, fnv1a(bytes.data(), body_size));
    if (bytes.compare(body_size + 6, 16, want) != 0)
        return fail("checksum mismatch (corrupt or edited model file)");
    std::istringstream in(bytes.substr(magic.size(), body_size - magic.size()));
    std::string key, features, segmentation;
    in >> key >> features;
    if (key != "features" || (features != "book" && features != "extended" &&
                              features != "topology" && features != "profile"))
        return fail(
            "line 2: expected 'features book', 'features extended', 'features topology' or "
            "'features profile'");
    in >> key >> segmentation;
    if (key != "segmentation" || (segmentation != "morphology" && segmentation != "likelihood"))
        return fail("line 3: expected 'segmentation morphology' or 'segmentation likelihood'");
    std::string rest;
    std::getline(in, rest);
    int threshold = kDefaultThreshold, single = 0;
    if (!rest.empty()) {
        std::istringstream r(rest);
        std::string word, extra;
        long n = 0, m = 0;
        bool ok = segmentation == "likelihood" && (r >> word >> n) && word == "threshold" &&
                  n >= 1 && n <= 255;
        if (ok && (r >> word)) ok = word == "single" && (r >> m) && m > n && m <= 255;
        if (!ok || (r >> extra))
            return fail(
                "line 3: expected 'segmentation likelihood threshold N' (1..255), optionally "
                "followed by 'single M' (N < M <= 255), got '" +
                key + " " + segmentation + rest + "'");
        threshold = static_cast<int>(n);
        single = static_cast<int>(m);
    }
    const GestureFeatureSet fs_set = features == "book"       ? GestureFeatureSet::kBook
                                     : features == "extended" ? GestureFeatureSet::kExtended
                                     : features == "topology" ? GestureFeatureSet::kTopology
                                                              : GestureFeatureSet::kProfile;
    const int nf = GestureFeatures::count(base_feature_set(fs_set));
    const int classes =
        fs_set == GestureFeatureSet::kBook ? kGestureLabelCount : kGestureLabelCount + 1;
    const std::size_t net_at = bytes.find('\n', bytes.find('\n', magic.size()) + 1) + 1;
    cv::Ptr<cv::ml::ANN_MLP> ann, two, profile;
    try {
        cv::FileStorage fs(
            bytes.substr(net_at, body_size - net_at),
            cv::FileStorage::READ | cv::FileStorage::MEMORY | cv::FileStorage::FORMAT_YAML);
        if (!fs.isOpened() || fs[kNode].empty()) return fail("no network in the file");
        const std::string shape = " is not " + std::to_string(nf) + "-N-" +
                                  std::to_string(classes) +
                                  " (2 <= N <= " + std::to_string(kGestureMaxHidden) +
                                  ") for the '" + features + "' features: ";
        if (const std::string why = network_shape_error(fs[kNode], nf, classes); !why.empty())
            return fail("the network" + shape + why);
        ann = cv::ml::ANN_MLP::create();
        ann->read(fs[kNode]);
        if (!fs[kTwoToolNode].empty()) {
            if (fs_set == GestureFeatureSet::kBook)
                return fail(
                    "a two-tool network with the book's features (extended, topology or profile "
                    "only)");
            if (const std::string why = network_shape_error(fs[kTwoToolNode], nf, classes);
                !why.empty())
                return fail("the two-tool network" + shape + why);
            two = cv::ml::ANN_MLP::create();
            two->read(fs[kTwoToolNode]);
        }
        if (fs_set == GestureFeatureSet::kProfile) {
            if (fs[kProfileNode].empty())
                return fail("no profile network (the 'profile' features)");
            if (const std::string why =
                    network_shape_error(fs[kProfileNode], GestureFeatures::kProfileCount, classes);
                !why.empty())
                return fail("the profile network is not " +
                            std::to_string(GestureFeatures::kProfileCount) + "-N-" +
                            std::to_string(classes) + ": " + why);
            profile = cv::ml::ANN_MLP::create();
            profile->read(fs[kProfileNode]);
        } else if (!fs[kProfileNode].empty()) {
            return fail("a profile network with the '" + features + "' features (profile only)");
        }
    } catch (const cv::Exception& e) {
        return fail("unreadable network (" + e.msg + ")");
    }
    if (!ann->isTrained() || (!two.empty() && !two->isTrained()) ||
        (!profile.empty() && !profile->isTrained()))
        return fail("unreadable network (OpenCV did not load it)");
    net_->ann = ann;
    net_->two_tool = two;
    net_->profile = profile;
    features_ = fs_set;
    segmentation_ = segmentation == "morphology" ? GestureSegmentation::kMorphology
                                                 : GestureSegmentation::kLikelihood;
    threshold_ = threshold;
    single_threshold_ = single;
    return true;
}

bool GestureClassifier::load(const std::string& path, std::string& error) {
    std::ifstream f(path, std::ios::binary);
    if (!f) {
        error = path + ": cannot open";
        return false;
    }
    std::ostringstream s;
    s << f.rdbuf();
    return parse(s.str(), path, error);
}

}  // namespace endotower::vision
