// endotower calibrate: the scope's calibration from image folders (docs/calibration.md).
// OpenCV's calibration on a target (chessboard, circle grids, ChArUco) and the book's
// procedure (white background, square chart, two-dot marker), a comparison of the
// two, and one calibration file per scope, written atomically.
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <opencv2/imgcodecs.hpp>
#include <regex>
#include <string>
#include <vector>

#include "calibrate_live.hpp"
#include "commands.hpp"
#include "endotower/calibration/book_calibration.hpp"
#include "endotower/calibration/calibration_file.hpp"
#include "endotower/calibration/undistorter.hpp"
#include "endotower/calibration/zhang_calibration.hpp"
#include "endotower/system/syscall.hpp"

namespace endotower::firmware {

namespace {

namespace fs = std::filesystem;
using namespace endotower::calibration;

void print_calibrate_help() {
    std::printf(
        "usage: endotower calibrate --images DIR|--live BOARD --target TARGET [--spacing MM|A,B]\n"
        "                           [--model pinhole|fisheye|book] --out FILE [--scope NAME]\n"
        "                           [--white DIR] [--chart DIR] [--marker DIR] [options]\n\n"
        "Calibrates the endoscope from image folders and writes one calibration file per\n"
        "scope (JSON: fx, fy, cx, cy, distortion, rms, ...; docs/calibration.md), atomically:\n"
        "on any error the previous file is untouched.\n\n"
        "  --images DIR     images of the target (every png/jpg/bmp/tif in DIR, one size)\n"
        "  --live BOARD     instead of --images: views of the target from the board's camera\n"
        "                   (its capture: device, or its sim.input replayed), kept as the\n"
        "                   technician moves and tilts the target (OpenCV targets only)\n"
        "  --views N        --live: views to keep, default 15 (at least 4)\n"
        "  --save-views DIR --live: also write the kept views there as PNG\n"
        "  --undistorted DIR after writing the file, the images undistorted with it (the\n"
        "                   firmware's remap) as PNG, to check that straight edges are\n"
        "                   straight\n"
        "  --target T       chessboard:COLSxROWS (inner corners) | circles:COLSxROWS |\n"
        "                   asymmetric-circles:COLSxROWS | charuco:COLSxROWS[:DICT] |\n"
        "                   squares (the book's chart: --images are chart images, --model book)\n"
        "  --spacing S      target spacing in mm: MM, or A,B (asymmetric circles: along a row,\n"
        "                   between rows, odd rows shifted A/2; one value S = OpenCV's 2S,S;\n"
        "                   charuco: SQUARE,MARKER; squares: the chart pitch, default 8)\n"
        "  --model M        pinhole (default) | fisheye: OpenCV; book: the book's ch. 2 model\n"
        "  --out FILE       the calibration file\n"
        "  --scope NAME     the scope's name or serial (default: FILE's stem)\n"
        "  --white DIR      white-background images: field-of-view circle and image centre\n"
        "  --chart DIR      the book's square chart at known distances (names like 050mm.png)\n"
        "  --chart-pitch MM chart pitch, default 8\n"
        "  --reference-mm Z chart distance for the focal length (eq. 2.17), default 50\n"
        "  --order N        odd order of the book's radial polynomial, default 3\n"
        "  --marker DIR     two-dot marker images at known distances (names like 070mm.png)\n"
        "  --marker-mm MM   the marker's dot separation, default 10\n"
        "  --zero-tangent   pinhole: no tangential distortion (p1 = p2 = 0)\n\n"
        "The book's steps run when --white is given (and --chart or a squares target); with\n"
        "both methods a comparison is printed (reprojection error on the target views,\n"
        "distance error on the chart). Exit status: 0 written, 1 failed while running or\n"
        "writing, 2 bad usage or input (the message names the image and what is missing).\n");
}

int usage_error(const std::string& m) {
    std::fprintf(stderr, "endotower calibrate: %s\n(see 'endotower calibrate --help')\n",
                 m.c_str());
    return kExitBadInput;
}

int input_error(const std::string& m) {
    std::fprintf(stderr, "endotower calibrate: %s\n", m.c_str());
    return kExitBadInput;
}

bool parse_number(const std::string& s, double lo, double hi, double& out) {
    char* end = nullptr;
    out = std::strtod(s.c_str(), &end);
    return !s.empty() && *end == 0 && out >= lo && out <= hi;
}

// "050mm.png", "marker_70mm.jpg", "12.5mm-a.png" -> the millimetres; 0 when none.
double distance_from_name(const std::string& name) {
    static const std::regex re("([0-9]+(\\.[0-9]+)?)mm");
    std::smatch m;
    return std::regex_search(name, m, re) ? std::stod(m[1]) : 0.0;
}

bool load_folder(const std::string& dir, std::vector<GrayImage>& out, std::string& error) {
    std::vector<std::string> paths;
    if (!list_images(dir, paths, error)) return false;
    for (const std::string& p : paths) {
        GrayImage g;
        if (!load_gray_image(p, g, error)) return false;
        if (!out.empty() && (g.width != out.front().width || g.height != out.front().height)) {
            error = p + ": image size " + std::to_string(g.width) + "x" + std::to_string(g.height) +
                    " differs from " + out.front().name + " (" + std::to_string(out.front().width) +
                    "x" + std::to_string(out.front().height) + "): mixed sizes";
            return false;
        }
        out.push_back(std::move(g));
    }
    return true;
}

bool load_distances(const std::string& dir, std::vector<DistanceImage>& out, std::string& error) {
    std::vector<GrayImage> imgs;
    if (!load_folder(dir, imgs, error)) return false;
    for (GrayImage& g : imgs) {
        const double z = distance_from_name(g.name);
        out.push_back({std::move(g), z});
    }
    return true;
}

std::string list(const std::vector<double>& v) {
    std::string s = "[";
    char b[32];
    for (std::size_t i = 0; i < v.size(); ++i) {
        std::snprintf(b, sizeof b, "%s%.6g", i ? ", " : "", v[i]);
        s += b;
    }
    return s + "]";
}

void print_book(const BookResult& b, int order) {
    std::printf("book (ch. 2): field of view centre (%.2f, %.2f) radius %.2f px (spread %.2f px)\n",
                b.fov.cx, b.fov.cy, b.fov.radius, b.fov_spread_px);
    std::printf(
        "  centre squares: Dx %.3f Dy %.3f px, Sx/Sy %.4f (eq. 2.4); fx %.2f fy %.2f px (eq. "
        "2.17)\n",
        b.reference.dx, b.reference.dy, b.reference.sx_over_sy, b.fx, b.fy);
    std::printf(
        "  order-%d radial polynomial about (%.2f, %.2f): k %s, total error %.4f, RMS %.3f px (%zu "
        "squares "
        "of %s)\n",
        order, b.distortion.fit.poly.cx, b.distortion.fit.poly.cy,
        list(b.distortion.fit.poly.k).c_str(), b.distortion.fit.total_error, b.radial_rms_px(),
        b.distortion.samples.size(), b.distortion_image.c_str());
    for (const auto& d : b.distances)
        std::printf("  table 2.3: %s actual %.1f mm, computed %.2f mm, error %.2f mm\n",
                    d.image.c_str(), d.actual_mm, d.computed_mm, d.computed_mm - d.actual_mm);
    if (b.separation)
        for (std::size_t i = 0; i < b.separation->distances_mm.size(); ++i)
            std::printf("  separation: %.1f mm %.2f px (pinhole %.2f px, %+.1f%%)\n",
                        b.separation->distances_mm[i], b.separation->separation_px[i],
                        b.pinhole_px[i],
                        100.0 * (b.separation->separation_px[i] / b.pinhole_px[i] - 1));
}

// The calibration's own remap (Undistorter, as the firmware would run it per frame)
// over the images it was made from, as PNGs named after them in `dir`, each written
// atomically: the technician checks that straight edges came out straight.
bool write_undistorted(const Calibration& cal, const std::vector<const GrayImage*>& images,
                       const std::string& dir, int& written, std::string& error) {
    Undistorter u;
    if (!u.init(cal, error)) return false;
    std::error_code ec;
    fs::create_directories(dir, ec);
    if (ec) {
        error = "cannot create " + dir + ": " + ec.message();
        return false;
    }
    cv::Mat out(cal.height, cal.width, CV_8UC1);
    std::vector<std::uint8_t> png;
    for (const GrayImage* g : images) {
        if (g->width != cal.width || g->height != cal.height) {
            error = g->name + ": " + std::to_string(g->width) + "x" + std::to_string(g->height) +
                    ", the calibration is " + std::to_string(cal.width) + "x" +
                    std::to_string(cal.height);
            return false;
        }
        hal::Frame in, o;
        in.format = o.format = {g->width, g->height, g->width, hal::PixelFormat::kGray8};
        in.data = const_cast<std::uint8_t*>(g->pixels.data());
        o.data = out.data;
        if (!u.apply(in, o) || !cv::imencode(".png", out, png)) {
            error = g->name + ": cannot undistort or encode";
            return false;
        }
        const fs::path path = fs::path(dir) / (fs::path(g->name).stem().string() + ".png");
        if (!system::write_file_atomic(path.string(), std::string(png.begin(), png.end()), error))
            return false;
        ++written;
    }
    return true;
}

}  // namespace

int run_calibrate_command(const Args& args) {
    std::string images, target, spacing, model_name = "pinhole", out, scope, white, chart, marker;
    std::string live_board, save_views, undistorted;
    double chart_pitch = 8, reference_mm = 50, order = 3, marker_mm = 10, live_views = 15;
    bool zero_tangent = false;
    for (std::size_t i = 0; i < args.size(); ++i) {
        const std::string& k = args[i];
        if (k == "--help" || k == "-h") {
            print_calibrate_help();
            return kExitOk;
        }
        if (k == "--zero-tangent") {
            zero_tangent = true;
            continue;
        }
        static const char* kValued[] = {
            "--images",     "--target",     "--spacing",   "--model",       "--out",
            "--scope",      "--white",      "--chart",     "--chart-pitch", "--reference-mm",
            "--order",      "--marker",     "--marker-mm", "--live",        "--views",
            "--save-views", "--undistorted"};
        bool known = false;
        for (const char* o : kValued) known = known || k == o;
        if (!known) return usage_error("unknown option '" + k + "'");
        if (i + 1 >= args.size()) return usage_error("option " + k + " needs a value");
        const std::string& v = args[++i];
        if (k == "--images")
            images = v;
        else if (k == "--live")
            live_board = v;
        else if (k == "--save-views")
            save_views = v;
        else if (k == "--undistorted")
            undistorted = v;
        else if (k == "--views" &&
                 (!parse_number(v, 4, 500, live_views) || live_views != std::floor(live_views)))
            return usage_error("--views needs a whole number 4..500, got '" + v + "'");
        else if (k == "--target")
            target = v;
        else if (k == "--spacing")
            spacing = v;
        else if (k == "--model")
            model_name = v;
        else if (k == "--out")
            out = v;
        else if (k == "--scope")
            scope = v;
        else if (k == "--white")
            white = v;
        else if (k == "--chart")
            chart = v;
        else if (k == "--marker")
            marker = v;
        else if (k == "--chart-pitch" && !parse_number(v, 0.01, 1000, chart_pitch))
            return usage_error("--chart-pitch needs a distance in mm, got '" + v + "'");
        else if (k == "--reference-mm" && !parse_number(v, 1, 10000, reference_mm))
            return usage_error("--reference-mm needs a distance in mm, got '" + v + "'");
        else if (k == "--marker-mm" && !parse_number(v, 0.01, 1000, marker_mm))
            return usage_error("--marker-mm needs a distance in mm, got '" + v + "'");
        else if (k == "--order" && (!parse_number(v, 1, 9, order) || order != std::floor(order) ||
                                    static_cast<int>(order) % 2 == 0))
            return usage_error("--order needs an odd whole number 1..9, got '" + v + "'");
    }
    if (images.empty() && live_board.empty())
        return usage_error("give --images DIR or --live BOARD");
    if (!images.empty() && !live_board.empty())
        return usage_error("give --images DIR or --live BOARD, not both");
    if (live_board.empty() && !save_views.empty())
        return usage_error("--save-views goes with --live");
    if (target.empty()) return usage_error("give --target (e.g. chessboard:9x6)");
    if (out.empty()) return usage_error("give --out FILE");
    LensModel model;
    if (!parse_lens_model(model_name, model))
        return usage_error("--model must be pinhole, fisheye or book, got '" + model_name + "'");
    TargetSpec spec;
    std::string error;
    if (!parse_target(target, spacing, spec, error)) return usage_error(error);
    const bool squares = spec.kind == TargetKind::kSquares;
    if (squares && model != LensModel::kBook)
        return usage_error("the squares chart is the book's method: add --model book");
    if (squares && !live_board.empty())
        return usage_error(
            "--live takes OpenCV's targets; the book's squares chart takes image folders");
    if (squares && !spacing.empty()) chart_pitch = spec.spacing_a;
    if (model == LensModel::kBook && white.empty())
        return usage_error("--model book needs --white DIR (the image centre)");
    if (model == LensModel::kBook && !squares && chart.empty())
        return usage_error("--model book needs the square chart: --target squares, or --chart DIR");
    if (scope.empty()) scope = fs::path(out).stem().string();

    // The book's procedure, when its inputs are there.
    std::optional<BookResult> book;
    std::vector<DistanceImage> chart_images;
    if (!white.empty() && (squares || !chart.empty())) {
        BookInputs in;
        if (!load_folder(white, in.white, error) ||
            !load_distances(squares ? images : chart, in.chart, error) ||
            (!marker.empty() && !load_distances(marker, in.marker, error)))
            return input_error(error);
        in.pitch_mm = chart_pitch;
        in.reference_mm = reference_mm;
        in.order = static_cast<int>(order);
        in.marker_mm = marker_mm;
        BookResult b;
        if (!run_book_calibration(in, b, error)) return input_error(error);
        book = std::move(b);
        chart_images = std::move(in.chart);
    } else if (!marker.empty()) {
        return usage_error(
            "--marker needs the book's steps: give --white DIR and a chart (--chart DIR)");
    }

    // OpenCV's calibration on the target views.
    std::optional<ZhangResult> zhang;
    std::vector<View> views;
    std::vector<GrayImage> imgs;
    if (!squares) {
        std::vector<std::string> missing;
        if (!live_board.empty()) {
            LiveViews live;
            const LiveViewOptions lo{
                .board = live_board, .views = static_cast<int>(live_views), .save_dir = save_views};
            if (!capture_live_views(lo, spec, live, error)) return input_error(error);
            if (live.views.size() < 4)
                return input_error(live.source + ": only " + std::to_string(live.views.size()) +
                                   " distinct views of the target in " +
                                   std::to_string(live.frames) + " frames (need 4): is it " +
                                   target + ", in focus, and moved between views?");
            imgs = std::move(live.images);
            views = std::move(live.views);
        } else if (!load_folder(images, imgs, error)) {
            return input_error(error);
        }
        if (book && (imgs.front().width != book->width || imgs.front().height != book->height))
            return input_error(
                imgs.front().name +
                ": image size differs from the white-background images: mixed sizes");
        for (const GrayImage& g : imgs) {
            if (!live_board.empty()) break;  // detected while capturing
            View v;
            if (detect_target(g, spec, v, error))
                views.push_back(std::move(v));
            else
                missing.push_back(error);
        }
        for (const std::string& m : missing) std::printf("skipped %s\n", m.c_str());
        ZhangResult z;
        const LensModel zm =
            model == LensModel::kFisheye ? LensModel::kFisheye : LensModel::kPinhole;
        if (!calibrate_zhang(views, imgs.front().width, imgs.front().height, zm, z, error,
                             {.zero_tangent = zero_tangent}))
            return input_error(error + (missing.empty() ? ""
                                                        : " (" + std::to_string(missing.size()) +
                                                              " image(s) skipped, above)"));
        std::printf("OpenCV %s: %zu of %zu images used (%s)\n", to_string(zm), z.views.size(),
                    imgs.size(), target.c_str());
        std::printf("  fx %.2f fy %.2f cx %.2f cy %.2f px, distortion %s\n", z.fx, z.fy, z.cx, z.cy,
                    list(z.distortion).c_str());
        std::printf(
            "  RMS reprojection error %.3f px; target spacing error %.4f mm (points back-projected "
            "on the plane)\n",
            z.rms, z.spacing_error);
        for (const auto& d : z.dropped)
            std::printf("  dropped %s: %s\n", d.name.c_str(), d.reason.c_str());
        zhang = std::move(z);
    }
    if (book) print_book(*book, static_cast<int>(order));

    Calibration cal;
    if (model == LensModel::kBook) {
        cal = book->calibration(scope);
    } else {
        cal.scope = scope;
        cal.model = model;
        cal.width = zhang->width, cal.height = zhang->height;
        cal.fx = zhang->fx, cal.fy = zhang->fy, cal.cx = zhang->cx, cal.cy = zhang->cy;
        cal.distortion = zhang->distortion;
        cal.rms = zhang->rms;
        if (book) {
            cal.fov = book->fov;
            cal.book = book->distortion.fit.poly;
            cal.separation = book->separation;
        }
    }

    if (book && zhang) {
        // Each model on the other's ground: the target views and the chart distances.
        Calibration zc = cal;
        zc.model = zhang->model, zc.fx = zhang->fx, zc.fy = zhang->fy, zc.cx = zhang->cx,
        zc.cy = zhang->cy;
        zc.distortion = zhang->distortion;
        const Calibration bc = book->calibration(scope);
        double book_err = 0, cv_err = 0;
        int n = 0;
        for (const DistanceImage& c : chart_images) {
            double z = 0;
            if (!(c.distance_mm > 0) ||
                !opencv_chart_distance(zc, c.image, book->fov, chart_pitch, z, error))
                continue;
            for (const auto& d : book->distances)
                if (d.image == c.image.name) book_err += std::abs(d.computed_mm - d.actual_mm);
            cv_err += std::abs(z - c.distance_mm);
            ++n;
        }
        std::printf("comparison (book vs OpenCV %s):\n", to_string(zhang->model));
        std::printf("  reprojection RMS on the %zu target views: book %.3f px, OpenCV %.3f px\n",
                    zhang->views.size(), book_reprojection_rms(views, bc), zhang->rms);
        if (n > 0)
            std::printf(
                "  mean distance error on %d chart images (eq. 2.2): book %.2f mm, OpenCV %.2f "
                "mm\n",
                n, book_err / n, cv_err / n);
    }

    const std::string text = format_calibration(cal);
    Calibration check;
    if (!parse_calibration(text, out, check, error)) {
        std::fprintf(stderr, "endotower calibrate: the result does not validate: %s\n",
                     error.c_str());
        return kExitFailure;
    }
    if (!system::write_file_atomic(out, text, error)) {
        std::fprintf(stderr, "endotower calibrate: %s\n", error.c_str());
        return kExitFailure;
    }
    std::printf("wrote %s (scope %s, model %s, RMS %.3f px, hash %s)\n", out.c_str(), scope.c_str(),
                to_string(cal.model), cal.rms, content_hash(text).c_str());
    if (!undistorted.empty()) {
        std::vector<const GrayImage*> sources;
        for (const GrayImage& g : imgs) sources.push_back(&g);
        for (const DistanceImage& c : chart_images) sources.push_back(&c.image);
        int written = 0;
        if (!write_undistorted(cal, sources, undistorted, written, error)) {
            std::fprintf(stderr, "endotower calibrate: --undistorted: %s\n", error.c_str());
            return kExitFailure;
        }
        std::printf("wrote %d undistorted image(s) to %s\n", written, undistorted.c_str());
    }
    return kExitOk;
}

}  // namespace endotower::firmware
