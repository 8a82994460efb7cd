#include "analysis_chain.hpp"

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iterator>
#include <optional>

#include "endotower/app/stage_chain.hpp"
#include "endotower/app/status_badge.hpp"
#include "endotower/calibration/calibration_stage.hpp"
#include "endotower/calibration/undistorter.hpp"
#include "endotower/gles/gles_renderer.hpp"
#include "endotower/media/media_image.hpp"
#include "endotower/media/media_library.hpp"
#include "endotower/sci/sci_stage.hpp"
#include "endotower/vision/anchored_overlay_stage.hpp"
#include "endotower/vision/gesture_stage.hpp"
#include "endotower/vision/kalman_tool_tracker.hpp"
#include "endotower/vision/likelihood_tool_tracker.hpp"
#include "endotower/vision/strip_marker_stage.hpp"
#include "endotower/vision/tool_tracker_factory.hpp"
#include "endotower/vision/tool_tracking_stage.hpp"

namespace endotower::firmware {

namespace fs = std::filesystem;

struct AnalysisChain::Parts {
    app::StatusBadge badge;
    std::optional<vision::KalmanToolTracker> kalman;
    vision::ToolLikelihood tool_model;
    std::optional<vision::LikelihoodToolTracker> likelihood;
    std::unique_ptr<vision::ToolTracker> book_tracker;  // ekf, mog2, particle, ... (by name)
    std::optional<vision::ToolTrackingStage> tracking;
    calibration::Calibration cal;
    std::optional<calibration::CalibrationStage> calibration_stage;
    calibration::Undistorter undistorter;
    std::optional<vision::RegionTracker> region_tracker;
    std::optional<vision::RegionStage> regions;
    std::unique_ptr<hal::OverlayRenderer> anchor_renderer;  // its own context: own cache, slots
    std::vector<std::unique_ptr<media::MediaImage>> anchor_images;  // lent to `anchored`
    std::optional<vision::AnchoredOverlayStage> anchored;
    vision::GestureClassifier gesture_classifier;
    vision::ToolLikelihood gesture_tool_model;
    std::optional<vision::GestureSegmenter> gesture_segmenter;
    std::optional<vision::GestureStage> gesture_stage;
    std::optional<vision::StripMarkerTracker> marker_tracker;
    std::optional<vision::StripMarkerStage> markers;
    std::vector<media::MediaLibrary> media;  // the SCI's decoded images, lent to it
    std::optional<sci::SciStage> sci;
    app::StageChain chain;
};

namespace {

// The SCI's patient data (app/media): the images of each modality sub-folder (ct, xray,
// mri; file-name order), decoded now and registered with the renderer by the stage,
// and the patient record. What is missing or corrupt is said on stderr and in the
// overlay; the interface goes on.
sci::SciMedia load_sci_media(const BoardConfig& b, bool renderer,
                             std::vector<media::MediaLibrary>& libraries, const char* command) {
    sci::SciMedia m;
    std::string problems;
    auto problem = [&problems](const std::string& p) {
        problems += (problems.empty() ? "" : "; ") + p;
    };
    libraries.resize(sci::kModalityCount);
    std::error_code ec;
    if (!b.sci_media.empty() && !fs::is_directory(b.sci_media, ec))
        problem("media folder not found: " + b.sci_media);
    int slot = 0;
    for (std::size_t k = 0; k < sci::kModalityCount && !b.sci_media.empty(); ++k) {
        const fs::path dir =
            fs::path(b.sci_media) / std::string(sci::to_string(static_cast<sci::SciModality>(k)));
        if (!fs::is_directory(dir, ec)) continue;
        std::string error;
        if (!libraries[k].load(dir.string(), error)) {
            problem(error);
            continue;
        }
        // Each modality folder is a MediaLibrary of its own; the record is sci.patient_record.
        for (const std::string& p : libraries[k].problems())
            if (p.find(media::MediaLibrary::kPatientFile) == std::string::npos) problem(p);
        for (const media::MediaImage& img : libraries[k].images()) {
            m.names[k].push_back(img.name);
            // The renderer holds kMaxImages; the rest show their name only.
            const bool fits = renderer && slot < hal::OverlayRenderer::kMaxImages;
            m.slots[k].push_back(fits ? slot++ : -1);
            if (fits) m.uploads.push_back(img.view());
        }
    }
    if (!renderer)
        m.message = "image not drawn: no overlay renderer";
    else if (slot == hal::OverlayRenderer::kMaxImages)
        m.message = "image not loaded: the renderer holds 8";
    if (!b.sci_patient_record.empty()) {
        media::PatientRecord r;
        std::string error;
        if (!media::load_patient_record(b.sci_patient_record, r, error)) {
            problem(error);
            m.record_lines.push_back("Patient record unavailable:");
            m.record_lines.push_back(error.substr(0, 90));
        } else {
            m.record_lines.push_back("Name: " + r.name);
            m.record_lines.push_back("ID: " + r.id);
            if (!r.birth_date.empty()) m.record_lines.push_back("Born: " + r.birth_date);
            if (!r.procedure.empty()) m.record_lines.push_back("Procedure: " + r.procedure);
            std::size_t at = 0;
            while (at < r.notes.size()) {
                const std::size_t nl = std::min(r.notes.find('\n', at), r.notes.size());
                m.record_lines.push_back(r.notes.substr(at, nl - at));
                at = nl + 1;
            }
        }
    }
    if (!problems.empty()) {
        std::fprintf(stderr, "endotower %s: sci: %s\n", command, problems.c_str());
        if (m.message.empty() || renderer) m.message = problems.substr(0, 90);
    }
    return m;
}

// The corrected (pinhole) point whose source in the input image is `pt`: a fixed point,
// the distortion is mild. Borrows the undistorter; allocates nothing per call.
std::function<vision::Point2(vision::Point2)> corrected_point(const calibration::Undistorter& u) {
    return [&u](vision::Point2 pt) {
        vision::Point2 q = pt;
        for (int i = 0; i < 12; ++i) {
            const calibration::Point2 s = u.source_of(q.x, q.y);
            q.x += pt.x - s.x;
            q.y += pt.y - s.y;
        }
        return q;
    };
}

// The image anchored to region `id` (analysis.regions.media / PATH): decoded now and
// lent to the stage; a path that leads out of the folder (a symlink), or a missing or
// corrupt file, is said on stderr and shown at the region instead. The video goes on.
void load_anchor_image(const BoardConfig& b, int id, const std::string& path,
                       AnalysisChain::AnchorImages& images, vision::AnchoredOverlayStage& stage,
                       const char* command) {
    std::string problem;
    std::error_code ec;
    const fs::path base = fs::weakly_canonical(b.region_media, ec);
    const fs::path file = fs::weakly_canonical(fs::path(b.region_media) / path, ec);
    const fs::path rel = file.lexically_relative(base);
    auto image = std::make_unique<media::MediaImage>();
    if (b.region_media.empty())
        problem = "image not loaded: no media folder (analysis.regions.media)";
    else if (ec || rel.empty() || *rel.begin() == "..")
        problem = path + ": leads out of the media folder " + b.region_media;
    else if (!media::load_media_image(file.string(), *image, problem))
        problem = "image not loaded: " + problem;
    if (problem.empty()) {
        stage.set_image(id, image->view());
        images.push_back(std::move(image));
        return;
    }
    if (id < 0)
        std::fprintf(stderr, "endotower %s: analysis.regions.overlay: %s\n", command,
                     problem.c_str());
    else
        std::fprintf(stderr, "endotower %s: region %d: %s\n", command, id, problem.c_str());
    stage.set_image_problem(id, problem.substr(0, 90));
}

}  // namespace

AnalysisChain::AnalysisChain() : parts_(std::make_unique<Parts>()) {}
AnalysisChain::~AnalysisChain() = default;

app::AnalysisStage* AnalysisChain::stage() {
    return parts_->chain.size() == 0 ? nullptr : &parts_->chain;
}
const vision::RegionStage& AnalysisChain::regions() const {
    return *parts_->regions;
}

bool AnalysisChain::build(const BoardConfig& board, const hal::FrameFormat& input,
                          std::vector<vision::RegionMark> marks, hal::OverlayRenderer* renderer,
                          app::Log& log, const char* command, std::string& error) {
    Parts& p = *parts_;
    // The scope's calibration: validated now, named in every trace line.
    if (!board.calibration.empty()) {
        if (!calibration::load_calibration(board.calibration, p.cal, error)) {
            error += " (calibration in " + board.path + ")";
            return false;
        }
        std::ifstream in(board.calibration, std::ios::binary);
        const std::string bytes((std::istreambuf_iterator<char>(in)),
                                std::istreambuf_iterator<char>());
        const std::string hash = calibration::content_hash(bytes);
        std::printf("calibration: %s (scope %s, model %s, hash %s)\n", board.calibration.c_str(),
                    p.cal.scope.c_str(), calibration::to_string(p.cal.model), hash.c_str());
        p.calibration_stage.emplace(p.cal, board.calibration, hash);
    }

    vision::KalmanToolTrackerParams kalman_params;
    kalman_params.red_binarised = board.tracker == "kalman_red";
    p.kalman.emplace(kalman_params);
    if (board.tracker == "likelihood" && !p.tool_model.load(board.tool_model, error)) {
        error = "analysis.tool_model: " + error;
        return false;
    }
    p.likelihood.emplace(p.tool_model);
    p.book_tracker = vision::make_book_tracker(board.tracker);
    vision::ToolTracker& tracker = p.book_tracker ? *p.book_tracker
                                   : board.tracker == "likelihood"
                                       ? static_cast<vision::ToolTracker&>(*p.likelihood)
                                       : *p.kalman;
    p.tracking.emplace(tracker);

    vision::RegionTrackerParams region_params;
    vision::parse_region_descriptor(board.region_descriptor,
                                    region_params.descriptor);  // checked by the board parser
    region_params.redetect_interval = board.region_redetect_interval;
    region_params.min_inliers = board.region_min_inliers;
    region_params.detect_max_width = board.region_detect_max_width;
    region_params.propagate = board.region_propagate;
    p.region_tracker.emplace(region_params);
    p.regions.emplace(*p.region_tracker);
    const bool any_regions = !marks.empty() || board.region_mark_with_tool;
    if (board.region_mark_with_tool && board.tracker == "none")
        std::fprintf(
            stderr,
            "endotower %s: analysis.regions.mark_with_tool needs a tracker: no tip to mark with\n",
            command);
    // The pointer is the most confident tool of this frame (as the SCI's cursor): it marks
    // regions, and its gesture is the one the surgeon makes.
    const vision::ToolTrackingStage* tracking = &*p.tracking;
    const auto pointer = [tracking](vision::Point2& tip) {
        double best = 0;
        for (std::size_t i = 0; i < tracking->tool_count(); ++i) {
            const vision::ToolEstimate& t = tracking->tool(i);
            if (t.present && t.confidence > best) best = t.confidence, tip = t.tip;
        }
        return best > 0;
    };
    if (board.region_mark_with_tool) p.regions->enable_tool_marking({}, pointer);
    vision::RegionOverlay tool_overlay;
    vision::parse_region_overlay(board.region_overlay, tool_overlay, error);  // checked
    p.regions->set_tool_overlay(tool_overlay);
    // Anchored images and objects (issue 7) get a renderer of their own (the SCI's
    // caches its standing menu; two scenes through one would redraw both every frame).
    bool anchored = board.sci || (board.region_mark_with_tool &&
                                  tool_overlay.kind != vision::RegionOverlayKind::kMarkers);
    for (const vision::RegionMark& m : marks)
        anchored = anchored || m.overlay.kind != vision::RegionOverlayKind::kMarkers;
    if (any_regions && anchored) {
        bool draws = tool_overlay.kind != vision::RegionOverlayKind::kMarkers;
        for (const vision::RegionMark& m : marks)
            draws = draws || m.overlay.kind != vision::RegionOverlayKind::kMarkers;
        if (draws) {
            std::string why;
            p.anchor_renderer = gles::create_gles_renderer(why);
            if (!p.anchor_renderer)
                std::fprintf(stderr,
                             "endotower %s: regions: no overlay renderer for anchored images "
                             "and objects: %s\n",
                             command, why.c_str());
        }
        p.anchored.emplace(*p.regions, p.anchor_renderer.get(), log, board.region_depth_mm);
        for (const vision::RegionMark& m : marks)
            if (m.overlay.kind == vision::RegionOverlayKind::kImage)
                load_anchor_image(board, m.id, m.overlay.image, p.anchor_images, *p.anchored,
                                  command);
        if (tool_overlay.kind == vision::RegionOverlayKind::kImage)  // the board's, id -1
            load_anchor_image(board, -1, tool_overlay.image, p.anchor_images, *p.anchored, command);
    }
    for (vision::RegionMark& m : marks) p.regions->schedule(std::move(m));

    // Gestures (issue 6): a wrong or corrupt model disables them, never the video.
    bool gestures = false;
    if (board.gestures) {
        gestures = p.gesture_classifier.load(board.gesture_model, error);
        // The segmenter's own pixel model when the board names one (the shipped one leaves
        // out the tracker's real image, whose pink-tinged metal makes wet tissue's sheen
        // read as tool: docs/gestures.md), else the tracker's.
        const bool own = !board.gesture_tool_model.empty();
        if (gestures &&
            p.gesture_classifier.segmentation() == vision::GestureSegmentation::kLikelihood &&
            !p.gesture_tool_model.load(own ? board.gesture_tool_model : board.tool_model, error)) {
            error = std::string("the gesture model's likelihood segmentation needs ") +
                    (own ? "analysis.gestures.tool_model" : "analysis.tool_model") + ": " + error;
            gestures = false;
        }
        if (!gestures)
            std::fprintf(
                stderr, "endotower %s: analysis.gestures.model: %s; gesture recognition disabled\n",
                command, error.c_str());
        error.clear();
    }
    p.gesture_segmenter.emplace(&p.gesture_tool_model, p.gesture_classifier.segmenter_params());
    vision::GestureStageParams gesture_params;
    gesture_params.hold.hold_ms = board.gesture_hold_ms;
    p.gesture_stage.emplace(*p.gesture_segmenter, p.gesture_classifier, gesture_params);
    if (board.tracker != "none") p.gesture_stage->set_pointer(pointer);

    // The calibration check first: with fov_mask it blackens the analysis frame outside
    // the field of view, so no later stage detects anything there.
    if (p.calibration_stage) {
        p.calibration_stage->set_mask(board.fov_mask);
        p.chain.add(&*p.calibration_stage);
    }
    if (board.stage == "status_badge") p.chain.add(&p.badge);
    if (board.tracker != "none") p.chain.add(&*p.tracking);
    // With a calibration of this image size, the tracker's tools get their 3-D pose.
    hal::SceneCamera camera;
    if (p.calibration_stage) {
        if (p.cal.width != input.width || p.cal.height != input.height) {
            std::printf("calibration: %dx%d, the input is %dx%d: no 3-D tool pose\n", p.cal.width,
                        p.cal.height, input.width, input.height);
        } else if (!p.undistorter.init(p.cal, error)) {
            std::printf("calibration: %s: no 3-D tool pose\n", error.c_str());
            error.clear();
        } else {
            camera = {p.cal.fx, p.cal.fy, p.cal.cx, p.cal.cy};
            const auto to_corrected = corrected_point(p.undistorter);
            if (board.tracker != "none")
                p.tracking->set_camera({p.cal.fx, p.cal.fy, p.cal.cx, p.cal.cy}, to_corrected,
                                       board.tool_diameter_mm);
        }
    }
    // Strip markers (issue 6): millimetres with a calibration that has the two-dot table.
    if (board.markers) {
        vision::StripMarkerParams marker_params;
        marker_params.diameter_mm = board.tool_diameter_mm;
        p.marker_tracker.emplace(marker_params);
        p.markers.emplace(*p.marker_tracker);
        p.chain.add(&*p.markers);
        if (!p.calibration_stage || !p.cal.separation) {
            std::printf(
                "markers: no calibration with a separation table: positions in pixels only\n");
        } else if (!camera.valid()) {
            std::printf(
                "markers: the calibration does not fit the input: positions in pixels only\n");
        } else {
            const auto to_corrected = corrected_point(p.undistorter);
            p.marker_tracker->set_calibration(
                *p.cal.separation, {p.cal.fx, p.cal.fy, p.cal.cx, p.cal.cy}, to_corrected);
        }
    }
    if (gestures) p.chain.add(&*p.gesture_stage);
    if (any_regions) p.chain.add(&*p.regions);
    if (any_regions && p.anchored) {
        p.anchored->set_camera(camera);
        p.chain.add(&*p.anchored);
    }

    // The surgeon-computer interface, last: it reads the tools and the gesture.
    if (board.sci) {
        sci::SciParams sp;
        sci::parse_sci_layout(board.sci_layout, sp.layout);  // checked by the board parser
        sp.dwell_ms = board.sci_dwell_ms;
        sp.activation_hold_ms = board.sci_activation_hold_ms;
        sp.cross_hold_ms = board.sci_cross_hold_ms;
        sp.confirm_ms = board.sci_confirm_ms;
        if (board.tracker == "none")
            std::fprintf(stderr,
                         "endotower %s: sci: analysis.tracker is none: no cursor, only the handle "
                         "drives it\n",
                         command);
        p.sci.emplace(sp, board.tracker != "none" ? &*p.tracking : nullptr,
                      gestures ? &*p.gesture_stage : nullptr, renderer, log,
                      load_sci_media(board, renderer != nullptr, p.media, command));
        p.sci->set_camera(camera);
        // The image box's target marker rides on the first tracked region (issue 8).
        if (any_regions && p.anchored) p.sci->set_target_source(&*p.anchored);
        p.chain.add(&*p.sci);
    }
    return true;
}

}  // namespace endotower::firmware
