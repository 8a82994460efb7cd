#include "endotower/calibration/calibration_file.hpp"

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>

namespace endotower::calibration {

using nlohmann::json;

namespace {

// Past any endoscope's sensor; also keeps every size and radius the checks below loop
// over or multiply small (a hostile file must not make the parser run for minutes).
constexpr int kMaxImageSide = 16384;

struct Reader {
    const json& doc;
    const std::string& source;
    std::string& error;

    bool fail(const std::string& what) {
        error = source + ": " + what;
        return false;
    }
    bool number(const json& obj, const char* key, double& out, const std::string& path,
                bool positive) {
        const auto it = obj.find(key);
        if (it == obj.end()) return fail("missing field '" + path + key + "'");
        if (!it->is_number()) return fail("'" + path + key + "' must be a number");
        out = it->get<double>();
        if (!std::isfinite(out) || (positive && !(out > 0)))
            return fail("'" + path + key + "' must be " + (positive ? "a positive" : "a finite") +
                        " number");
        return true;
    }
    bool numbers(const json& obj, const char* key, std::vector<double>& out,
                 const std::string& path) {
        const auto it = obj.find(key);
        if (it == obj.end()) return fail("missing field '" + path + key + "'");
        if (!it->is_array()) return fail("'" + path + key + "' must be a list of numbers");
        out.clear();
        for (const json& v : *it) {
            if (!v.is_number() || !std::isfinite(v.get<double>()))
                return fail("'" + path + key + "' must be a list of finite numbers");
            out.push_back(v.get<double>());
        }
        return true;
    }
};

}  // namespace

std::string format_calibration(const Calibration& c) {
    nlohmann::ordered_json j;  // in the order people read them: the camera first
    j["fx"] = c.fx;
    j["fy"] = c.fy;
    j["cx"] = c.cx;
    j["cy"] = c.cy;
    j["distortion"] = c.distortion;
    j["rms"] = c.rms;
    j["model"] = to_string(c.model);
    j["scope"] = c.scope;
    j["image_size"] = {c.width, c.height};
    if (c.fov.valid()) j["fov"] = {{"cx", c.fov.cx}, {"cy", c.fov.cy}, {"radius", c.fov.radius}};
    if (c.book) j["book_polynomial"] = {{"cx", c.book->cx}, {"cy", c.book->cy}, {"k", c.book->k}};
    if (c.separation)
        j["separation"] = {{"marker_mm", c.separation->marker_mm},
                           {"distances_mm", c.separation->distances_mm},
                           {"separation_px", c.separation->separation_px}};
    return j.dump(2) + "\n";
}

bool parse_calibration(const std::string& text, const std::string& source, Calibration& out,
                       std::string& error) {
    json doc;
    try {
        doc = json::parse(text);
    } catch (const json::parse_error& e) {
        const std::size_t upto = std::min<std::size_t>(e.byte, text.size());
        const long line =
            1 + std::count(text.begin(), text.begin() + static_cast<long>(upto), '\n');
        error = source + ":" + std::to_string(line) + ": not valid JSON";
        return false;
    } catch (const json::exception&) {
        // The parser reports a number too large for a double (1e999) as out_of_range,
        // without a position (found by fuzz_calibration: it used to end the program).
        error = source + ": not valid JSON (a number out of range)";
        return false;
    }
    Reader r{doc, source, error};
    if (!doc.is_object()) return r.fail("not a JSON object");
    Calibration c;
    const auto model = doc.find("model");
    if (model == doc.end() || !model->is_string())
        return r.fail("missing field 'model' (pinhole, fisheye or book)");
    if (!parse_lens_model(model->get<std::string>(), c.model))
        return r.fail("'model' is '" + model->get<std::string>() + "' (pinhole, fisheye or book)");
    const auto scope = doc.find("scope");
    if (scope == doc.end() || !scope->is_string() || scope->get<std::string>().empty())
        return r.fail("missing field 'scope' (the scope's name or serial)");
    c.scope = scope->get<std::string>();
    const auto size = doc.find("image_size");
    // A side as a whole number in 1..kMaxImageSide, else 0 (JSON keeps non-negative
    // integers unsigned; nothing here narrows a huge one into range).
    auto side = [&](std::size_t i) -> int {
        const json& v = (*size)[i];
        if (!v.is_number_integer()) return 0;
        if (v.is_number_unsigned()) {
            const std::uint64_t u = v.get<std::uint64_t>();
            return u >= 1 && u <= static_cast<std::uint64_t>(kMaxImageSide) ? static_cast<int>(u)
                                                                            : 0;
        }
        const std::int64_t n = v.get<std::int64_t>();
        return n >= 1 && n <= kMaxImageSide ? static_cast<int>(n) : 0;
    };
    if (size == doc.end() || !size->is_array() || size->size() != 2 || side(0) == 0 || side(1) == 0)
        return r.fail("'image_size' must be [width, height], whole numbers 1.." +
                      std::to_string(kMaxImageSide));
    c.width = side(0);
    c.height = side(1);
    auto inside = [&](double x, double y) {
        return x >= 0 && x < c.width && y >= 0 && y < c.height;
    };
    if (!r.number(doc, "fx", c.fx, "", true) || !r.number(doc, "fy", c.fy, "", true) ||
        !r.number(doc, "cx", c.cx, "", false) || !r.number(doc, "cy", c.cy, "", false) ||
        !r.number(doc, "rms", c.rms, "", false) || !r.numbers(doc, "distortion", c.distortion, ""))
        return false;
    if (c.rms < 0) return r.fail("'rms' must not be negative");
    if (!inside(c.cx, c.cy)) return r.fail("the centre (cx, cy) lies outside the image");
    const std::size_t nd = c.distortion.size();
    if (c.model == LensModel::kPinhole && nd != 4 && nd != 5 && nd != 8 && nd != 12 && nd != 14)
        return r.fail("'distortion' has " + std::to_string(nd) +
                      " values; pinhole needs 4, 5, 8, 12 or 14");
    if (c.model == LensModel::kFisheye && nd != 4)
        return r.fail("'distortion' has " + std::to_string(nd) + " values; fisheye needs 4");
    if (c.model == LensModel::kBook && (nd < 1 || nd > 5))
        return r.fail("'distortion' has " + std::to_string(nd) +
                      " values; book needs 1..5 (orders 1..9)");
    const double r_max =
        std::hypot(std::max(c.cx, c.width - c.cx), std::max(c.cy, c.height - c.cy));
    if (const auto f = doc.find("fov"); f != doc.end()) {
        if (!f->is_object()) return r.fail("'fov' must be an object {cx, cy, radius}");
        if (!r.number(*f, "cx", c.fov.cx, "fov.", false) ||
            !r.number(*f, "cy", c.fov.cy, "fov.", false) ||
            !r.number(*f, "radius", c.fov.radius, "fov.", true))
            return false;
        if (!inside(c.fov.cx, c.fov.cy)) return r.fail("the 'fov' centre lies outside the image");
        const double diagonal = std::hypot(c.width, c.height);
        if (c.fov.radius > diagonal)
            return r.fail("'fov.radius' is larger than the image's diagonal (" +
                          std::to_string(static_cast<int>(diagonal)) + " px)");
    }
    if (const auto b = doc.find("book_polynomial"); b != doc.end()) {
        if (!b->is_object()) return r.fail("'book_polynomial' must be an object {cx, cy, k}");
        RadialPolynomial p;
        if (!r.number(*b, "cx", p.cx, "book_polynomial.", false) ||
            !r.number(*b, "cy", p.cy, "book_polynomial.", false) ||
            !r.numbers(*b, "k", p.k, "book_polynomial."))
            return false;
        if (p.k.empty() || p.k.size() > 5) return r.fail("'book_polynomial.k' needs 1..5 values");
        if (!inside(p.cx, p.cy))
            return r.fail("the 'book_polynomial' centre lies outside the image");
        const double lim = c.fov.valid() ? c.fov.radius : r_max;
        if (!p.monotonic(lim))
            return r.fail("'book_polynomial' is not monotonic within " +
                          std::to_string(static_cast<int>(lim)) +
                          " px (the corrected image would fold over)");
        c.book = p;
    }
    if (c.model == LensModel::kBook) {
        if (!c.book) c.book = RadialPolynomial{c.distortion, c.cx, c.cy};
        if (!RadialPolynomial{c.distortion, c.cx, c.cy}.monotonic(c.fov.valid() ? c.fov.radius
                                                                                : r_max))
            return r.fail("'distortion' (book polynomial) is not monotonic over the image");
    }
    if (const auto s = doc.find("separation"); s != doc.end()) {
        if (!s->is_object()) return r.fail("'separation' must be an object");
        SeparationTable t;
        if (!r.number(*s, "marker_mm", t.marker_mm, "separation.", true) ||
            !r.numbers(*s, "distances_mm", t.distances_mm, "separation.") ||
            !r.numbers(*s, "separation_px", t.separation_px, "separation."))
            return false;
        std::string e;
        if (!t.validate(e)) return r.fail(e);
        c.separation = t;
    }
    out = c;
    return true;
}

bool load_calibration(const std::string& path, Calibration& out, std::string& error) {
    std::ifstream in(path, std::ios::binary);
    if (!in) {
        error = path + ": cannot open the calibration file";
        return false;
    }
    std::ostringstream ss;
    ss << in.rdbuf();
    return parse_calibration(ss.str(), path, out, error);
}

std::string content_hash(const std::string& bytes) {
    std::uint64_t h = 14695981039346656037ull;
    for (unsigned char ch : bytes) {
        h ^= ch;
        h *= 1099511628211ull;
    }
    char buf[17];
    std::snprintf(buf, sizeof buf, "%016llx", static_cast<unsigned long long>(h));
    return buf;
}

}  // namespace endotower::calibration
