#include "endotower/calibration/target.hpp"

#include <cstdio>
#include <map>
#include <opencv2/aruco/charuco.hpp>
#include <opencv2/calib3d.hpp>
#include <opencv2/imgproc.hpp>

namespace endotower::calibration {

namespace {

bool parse_size(const std::string& s, int& cols, int& rows) {
    char x = 0;
    int consumed = 0;
    return std::sscanf(s.c_str(), "%d%c%d%n", &cols, &x, &rows, &consumed) == 3 && x == 'x' &&
           consumed == static_cast<int>(s.size()) && cols >= 2 && rows >= 2 && cols <= 100 &&
           rows <= 100;
}

const std::map<std::string, int>& dictionaries() {
    static const std::map<std::string, int> d = {
        {"DICT_4X4_50", cv::aruco::DICT_4X4_50},
        {"DICT_4X4_100", cv::aruco::DICT_4X4_100},
        {"DICT_4X4_250", cv::aruco::DICT_4X4_250},
        {"DICT_5X5_50", cv::aruco::DICT_5X5_50},
        {"DICT_5X5_100", cv::aruco::DICT_5X5_100},
        {"DICT_5X5_250", cv::aruco::DICT_5X5_250},
        {"DICT_6X6_50", cv::aruco::DICT_6X6_50},
        {"DICT_6X6_250", cv::aruco::DICT_6X6_250},
        {"DICT_7X7_50", cv::aruco::DICT_7X7_50},
        {"DICT_ARUCO_ORIGINAL", cv::aruco::DICT_ARUCO_ORIGINAL}};
    return d;
}

}  // namespace

bool parse_target(const std::string& target, const std::string& spacing, TargetSpec& out,
                  std::string& error) {
    const auto colon = target.find(':');
    const std::string kind = target.substr(0, colon);
    std::string rest = colon == std::string::npos ? "" : target.substr(colon + 1);
    TargetSpec t;
    if (kind == "chessboard")
        t.kind = TargetKind::kChessboard;
    else if (kind == "circles")
        t.kind = TargetKind::kCircles;
    else if (kind == "asymmetric-circles")
        t.kind = TargetKind::kAsymmetricCircles;
    else if (kind == "charuco")
        t.kind = TargetKind::kCharuco;
    else if (kind == "squares")
        t.kind = TargetKind::kSquares;
    else {
        error = "--target '" + target + "': unknown kind '" + kind +
                "' (chessboard, circles, asymmetric-circles, charuco, squares)";
        return false;
    }
    if (t.kind == TargetKind::kCharuco) {
        const auto c2 = rest.find(':');
        if (c2 != std::string::npos) {
            t.dictionary = rest.substr(c2 + 1);
            rest = rest.substr(0, c2);
            if (!dictionaries().count(t.dictionary)) {
                error =
                    "--target '" + target + "': unknown ArUco dictionary '" + t.dictionary + "'";
                return false;
            }
        }
    }
    if (t.kind == TargetKind::kSquares && rest.empty()) {
        t.cols = t.rows = 3;  // only the central squares are required
    } else if (!parse_size(rest, t.cols, t.rows)) {
        error = "--target '" + target + "': expected " + kind + ":COLSxROWS (e.g. chessboard:9x6)";
        return false;
    }
    double a = 1, b = 0;
    if (!spacing.empty()) {
        char comma = 0;
        int consumed = 0;
        const int n = std::sscanf(spacing.c_str(), "%lf%n%c%lf", &a, &consumed, &comma, &b);
        if (n == 1 && consumed == static_cast<int>(spacing.size())) {
            b = 0;
        } else if (!(n == 3 && comma == ',')) {
            error = "--spacing '" + spacing + "': expected MM or A,B (e.g. 25 or 3,1)";
            return false;
        }
        if (!(a > 0) || (n == 3 && !(b > 0))) {
            error = "--spacing '" + spacing + "': distances must be positive";
            return false;
        }
    }
    t.spacing_a = a;
    t.spacing_b = b > 0 ? b : a;
    if (t.kind == TargetKind::kAsymmetricCircles && b == 0) {
        t.spacing_a = 2 * a;  // OpenCV's layout: rows S apart, 2S along a row
        t.spacing_b = a;
    }
    if (t.kind == TargetKind::kCharuco) {
        if (b == 0) {
            error = "--spacing for charuco: give SQUARE,MARKER in mm (e.g. 20,15)";
            return false;
        }
        if (!(b < a)) {
            error = "--spacing '" + spacing + "': the marker must be smaller than the square";
            return false;
        }
    }
    out = t;
    return true;
}

bool detect_target(const GrayImage& image, const TargetSpec& spec, View& out, std::string& error) {
    const cv::Mat gray(image.height, image.width, CV_8UC1,
                       const_cast<std::uint8_t*>(image.pixels.data()));
    const cv::Size size(spec.cols, spec.rows);
    std::vector<cv::Point2f> pts;
    std::vector<cv::Point3f> obj;
    bool found = false;
    switch (spec.kind) {
        case TargetKind::kChessboard:
            found = cv::findChessboardCorners(
                gray, size, pts, cv::CALIB_CB_ADAPTIVE_THRESH | cv::CALIB_CB_NORMALIZE_IMAGE);
            if (found)
                cv::cornerSubPix(
                    gray, pts, cv::Size(11, 11), cv::Size(-1, -1),
                    cv::TermCriteria(cv::TermCriteria::EPS | cv::TermCriteria::COUNT, 50, 1e-3));
            for (int r = 0; r < spec.rows; ++r)
                for (int c = 0; c < spec.cols; ++c)
                    obj.emplace_back(c * spec.spacing_a, r * spec.spacing_b, 0);
            break;
        case TargetKind::kCircles:
            found = cv::findCirclesGrid(gray, size, pts, cv::CALIB_CB_SYMMETRIC_GRID);
            for (int r = 0; r < spec.rows; ++r)
                for (int c = 0; c < spec.cols; ++c)
                    obj.emplace_back(c * spec.spacing_a, r * spec.spacing_b, 0);
            break;
        case TargetKind::kAsymmetricCircles:
            found = cv::findCirclesGrid(gray, size, pts, cv::CALIB_CB_ASYMMETRIC_GRID);
            for (int r = 0; r < spec.rows; ++r)
                for (int c = 0; c < spec.cols; ++c)
                    obj.emplace_back(c * spec.spacing_a + (r % 2) * 0.5 * spec.spacing_a,
                                     r * spec.spacing_b, 0);
            break;
        case TargetKind::kCharuco: {
            const auto dict =
                cv::aruco::getPredefinedDictionary(dictionaries().at(spec.dictionary));
            const auto board = cv::aruco::CharucoBoard::create(
                spec.cols, spec.rows, static_cast<float>(spec.spacing_a),
                static_cast<float>(spec.spacing_b), dict);
            std::vector<int> ids, corner_ids;
            std::vector<std::vector<cv::Point2f>> corners;
            cv::aruco::detectMarkers(gray, dict, corners, ids);
            if (!ids.empty())
                cv::aruco::interpolateCornersCharuco(corners, ids, gray, board, pts, corner_ids);
            // Six corners pin a homography with margin; fewer give unstable views.
            found = corner_ids.size() >= 6;
            if (found) {
                obj.clear();
                for (int id : corner_ids) obj.push_back(board->chessboardCorners[id]);
            } else {
                error = image.name + ": ChArUco board not found (" + std::to_string(ids.size()) +
                        " markers, " + std::to_string(corner_ids.size()) +
                        " corners; need 6 corners)";
                return false;
            }
            break;
        }
        case TargetKind::kSquares:
            error = image.name + ": the squares chart is the book's model (--model book)";
            return false;
    }
    if (!found) {
        error = image.name + ": grid not found (" + std::to_string(spec.cols) + "x" +
                std::to_string(spec.rows) +
                (spec.kind == TargetKind::kChessboard ? " inner corners" : " circles") + ")";
        return false;
    }
    out.name = image.name;
    out.image_points.clear();
    out.object_points.clear();
    for (const cv::Point2f& p : pts) out.image_points.push_back({p.x, p.y});
    for (const cv::Point3f& p : obj) out.object_points.push_back({p.x, p.y, p.z});
    return true;
}

}  // namespace endotower::calibration
