// The calibration file: one per scope (name or serial), JSON. Top-level fields that
// outside checks read: fx, fy, cx, cy (px), distortion (list), rms (px). Also model
// ("pinhole" | "fisheye" | "book"), scope, image_size [w, h], and when measured: fov
// {cx, cy, radius}, book_polynomial {cx, cy, k: [...]} (the book's dr polynomial),
// separation {marker_mm, distances_mm: [...], separation_px: [...]}.
// For model "book", distortion is the book polynomial's k and (cx, cy) its centre.
// Format in docs/calibration.md. Writing is the caller's (atomic, drivers/system).
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "endotower/calibration/field_of_view.hpp"
#include "endotower/calibration/radial_polynomial.hpp"
#include "endotower/calibration/separation_table.hpp"
#include "endotower/calibration/zhang_calibration.hpp"

namespace endotower::calibration {

struct Calibration {
    std::string scope;  // name or serial
    LensModel model = LensModel::kPinhole;
    int width = 0, height = 0;
    double fx = 0, fy = 0, cx = 0, cy = 0;
    std::vector<double> distortion;
    double rms = 0;
    FovCircle fov;                         // radius 0: not measured
    std::optional<RadialPolynomial> book;  // the book's radial polynomial
    std::optional<SeparationTable> separation;
};

// The document (pretty JSON, trailing newline).
std::string format_calibration(const Calibration& c);

// Parses and validates: every required field present with the right type, fx, fy,
// image size and rms positive / non-negative and finite, (cx, cy) inside the image,
// the distortion length fits the model (pinhole 4, 5, 8, 12 or 14; fisheye 4; book
// 1..5), the book polynomial monotonic over the image, the separation table valid.
// Errors read "SOURCE: what is wrong" (SOURCE:LINE for syntax errors).
bool parse_calibration(const std::string& text, const std::string& source, Calibration& out,
                       std::string& error);
bool load_calibration(const std::string& path, Calibration& out, std::string& error);

// FNV-1a 64-bit of the file's bytes, 16 hex digits: names the calibration in traces.
std::string content_hash(const std::string& bytes);

}  // namespace endotower::calibration
