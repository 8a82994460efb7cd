#include "endotower/scene/recording.hpp"

#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <sstream>
#include <vector>

#include "endotower/scene/renderer.hpp"
#include "endotower/scene/scenario.hpp"

namespace endotower::scene {

namespace {

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

double ms_since(Clock::time_point t0) {
    return std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
}

bool write_text(const fs::path& p, const std::string& text, std::string& error) {
    std::ofstream out(p, std::ios::binary);
    out << text;
    out.close();
    if (!out) {
        error = p.string() + ": cannot write: " + std::strerror(errno);
        return false;
    }
    return true;
}

}  // namespace

RecordingResult write_recording(const RecordingOptions& o, RecordingStats& stats,
                                std::string& error) {
    const auto t_setup = Clock::now();
    std::string text;
    {
        std::ifstream in(o.scenario_path, std::ios::binary);
        if (!in) {
            error = o.scenario_path + ": cannot open the scenario file";
            return RecordingResult::kBadInput;
        }
        std::ostringstream ss;
        ss << in.rdbuf();
        text = ss.str();
    }
    Scenario sc;
    if (!parse_scenario(text, o.scenario_path, sc, error)) return RecordingResult::kBadInput;
    if (o.scale != 1.0) scale_durations(sc, o.scale);
    if (o.frames > 0) sc.frames = o.frames;
    if (o.width > 0) sc.width = o.width, sc.height = o.height;
    const std::uint64_t seed = o.seed.value_or(sc.seed);

    const fs::path out(o.out_dir);
    if (out.empty() || out.filename().empty()) {
        error = "--out needs a directory name, got '" + o.out_dir + "'";
        return RecordingResult::kBadInput;
    }
    std::error_code ec;
    const fs::path parent = out.has_parent_path() ? out.parent_path() : fs::path(".");
    fs::create_directories(parent, ec);
    if (fs::exists(out) &&
        !(fs::is_directory(out) && (fs::is_empty(out) || fs::exists(out / "truth.jsonl")))) {
        error = out.string() + ": exists and is not an earlier recording; refusing to replace it";
        return RecordingResult::kBadInput;
    }
    std::string tmpl = (parent / (out.filename().string() + ".tmp-XXXXXX")).string();
    std::vector<char> buf(tmpl.begin(), tmpl.end());
    buf.push_back(0);
    if (mkdtemp(buf.data()) == nullptr) {
        error = parent.string() + ": cannot create a temporary directory: " + std::strerror(errno);
        return RecordingResult::kBadInput;
    }
    const fs::path tmp(buf.data());
    auto fail = [&](RecordingResult r) {
        fs::remove_all(tmp, ec);
        return r;
    };
    fs::create_directory(tmp / "frames", ec);
    if (o.labels) fs::create_directory(tmp / "labels", ec);
    std::vector<std::uint8_t> labels;

    SceneRenderer renderer;
    if (!renderer.init(sc, seed, error)) return fail(RecordingResult::kBadInput);
    stats.setup_ms = ms_since(t_setup);
    std::string truth_text;
    Image image;
    FrameTruth truth;
    double render_ms = 0, write_ms = 0;
    const std::vector<int> png = {cv::IMWRITE_PNG_COMPRESSION, 1};
    for (int i = 0; i < sc.frames; ++i) {
        const auto t0 = Clock::now();
        renderer.render(i, image, truth);
        render_ms += ms_since(t0);
        const auto t1 = Clock::now();
        truth_text += truth_json_line(truth, renderer.camera(), sc);
        truth_text += '\n';
        char name[32];
        std::snprintf(name, sizeof name, "%06d.png", i);
        const cv::Mat m(image.height, image.width, CV_8UC3, image.bgr.data());
        const fs::path p = tmp / "frames" / name;
        bool ok = false;
        try {
            ok = cv::imwrite(p.string(), m, png);
        } catch (const cv::Exception&) {
            ok = false;
        }
        if (!ok) {
            error = p.string() + ": cannot write the frame";
            return fail(RecordingResult::kFailed);
        }
        if (o.labels) {
            renderer.tool_labels(labels);
            const cv::Mat l(image.height, image.width, CV_8U, labels.data());
            const fs::path lp = tmp / "labels" / name;
            try {
                ok = cv::imwrite(lp.string(), l, png);
            } catch (const cv::Exception&) {
                ok = false;
            }
            if (!ok) {
                error = lp.string() + ": cannot write the labels";
                return fail(RecordingResult::kFailed);
            }
        }
        write_ms += ms_since(t1);
    }
    if (!write_text(tmp / "truth.jsonl", truth_text, error) ||
        !write_text(tmp / "scenario.yaml", text, error))
        return fail(RecordingResult::kFailed);
    ::sync();
    // Swap in: an earlier recording moves aside first, and goes once the new one is in place.
    fs::path old;
    if (fs::exists(out)) {
        old = tmp;
        old += ".old";
        fs::rename(out, old, ec);
        if (ec) {
            error = out.string() + ": cannot move the earlier recording aside: " + ec.message();
            return fail(RecordingResult::kFailed);
        }
    }
    fs::rename(tmp, out, ec);
    if (ec) {
        error = out.string() + ": cannot rename the finished recording into place: " + ec.message();
        if (!old.empty()) fs::rename(old, out, ec);
        return fail(RecordingResult::kFailed);
    }
    if (!old.empty()) fs::remove_all(old, ec);
    stats.frames = sc.frames;
    stats.render_ms_per_frame = render_ms / std::max(1, sc.frames);
    stats.write_ms_per_frame = write_ms / std::max(1, sc.frames);
    return RecordingResult::kOk;
}

}  // namespace endotower::scene
