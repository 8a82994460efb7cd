// The report's PNG plots, drawn with OpenCV: white background, titled axes with
// ticks and grid, a legend, and a per-frame outcome strip under time plots.
#include <algorithm>
#include <cmath>
#include <map>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "endotower/eval/assignment.hpp"
#include "endotower/eval/report.hpp"
#include "report_common.hpp"

namespace endotower::eval {

using detail::fmt;

namespace {

const cv::Scalar kBlack(30, 30, 30), kGrid(225, 225, 225), kAxis(90, 90, 90);
const cv::Scalar kGreen(80, 170, 60), kRed(60, 60, 215), kGrey(175, 175, 175), kAmber(40, 170, 240);
const cv::Scalar kSeries[] = {{190, 110, 30}, {30, 130, 240}, {150, 60, 150}, {40, 150, 150}};
constexpr int kFont = cv::FONT_HERSHEY_SIMPLEX;

void text(cv::Mat& img, const std::string& s, int x, int y, double scale = 0.5,
          const cv::Scalar& c = kBlack, int thick = 1) {
    cv::putText(img, s, {x, y}, kFont, scale, c, thick, cv::LINE_AA);
}
int text_width(const std::string& s, double scale = 0.5, int thick = 1) {
    int base = 0;
    return cv::getTextSize(s, kFont, scale, thick, &base).width;
}
// Text centred on x.
void text_c(cv::Mat& img, const std::string& s, int x, int y, double scale = 0.5,
            const cv::Scalar& c = kBlack, int thick = 1) {
    text(img, s, x - text_width(s, scale, thick) / 2, y, scale, c, thick);
}
// Vertical text (reading bottom to top) centred on (x, y).
void text_v(cv::Mat& img, const std::string& s, int x, int y, double scale = 0.55) {
    int base = 0;
    const cv::Size sz = cv::getTextSize(s, kFont, scale, 1, &base);
    cv::Mat t(sz.height + base + 4, sz.width + 4, CV_8UC3, cv::Scalar(255, 255, 255));
    cv::putText(t, s, {2, sz.height + 2}, kFont, scale, kBlack, 1, cv::LINE_AA);
    cv::rotate(t, t, cv::ROTATE_90_COUNTERCLOCKWISE);
    const cv::Rect r(x - t.cols / 2, y - t.rows / 2, t.cols, t.rows);
    if ((r & cv::Rect(0, 0, img.cols, img.rows)) == r) t.copyTo(img(r));
}

// 1, 2 or 5 x 10^k, giving about `n` ticks over [0, hi].
double nice_step(double hi, int n) {
    const double raw = std::max(hi, 1e-9) / n;
    const double p = std::pow(10.0, std::floor(std::log10(raw)));
    for (double m : {1.0, 2.0, 5.0, 10.0})
        if (raw <= m * p) return m * p;
    return 10 * p;
}
std::string tick_label(double v, double step) {
    return step >= 1 ? fmt("%.0f", v) : step >= 0.1 ? fmt("%.1f", v) : fmt("%.2f", v);
}

// A time plot: x = frame, y = value; plot area `area` in the image.
struct Axes {
    cv::Rect area;
    double x0 = 0, x1 = 1, y1 = 1;
    int px(double x) const { return area.x + static_cast<int>(std::lround((x - x0) / std::max(x1 - x0, 1e-9) * area.width)); }
    int py(double y) const {
        return area.y + area.height - static_cast<int>(std::lround(std::clamp(y / y1, 0.0, 1.0) * area.height));
    }
};

void draw_axes(cv::Mat& img, const Axes& a, const std::string& title, const std::string& xlabel,
               const std::string& ylabel) {
    const double ys = nice_step(a.y1, 6);
    for (double v = 0; v <= a.y1 + 1e-9; v += ys) {
        cv::line(img, {a.area.x, a.py(v)}, {a.area.br().x, a.py(v)}, kGrid, 1);
        const std::string l = tick_label(v, ys);
        text(img, l, a.area.x - 8 - text_width(l, 0.45), a.py(v) + 5, 0.45);
    }
    const double xs = nice_step(a.x1 - a.x0, 10);
    for (double v = std::ceil(a.x0 / xs) * xs; v <= a.x1 + 1e-9; v += xs) {
        cv::line(img, {a.px(v), a.area.y}, {a.px(v), a.area.br().y}, kGrid, 1);
        text_c(img, tick_label(v, xs), a.px(v), a.area.br().y + 18, 0.45);
    }
    cv::rectangle(img, a.area, kAxis, 1);
    text_c(img, title, a.area.x + a.area.width / 2, 30, 0.7, kBlack, 2);
    text_c(img, xlabel, a.area.x + a.area.width / 2, img.rows - 12, 0.55);
    text_v(img, ylabel, 22, a.area.y + a.area.height / 2);
}

// Legend entries: colour, text, line or filled box.
struct Entry {
    cv::Scalar color;
    std::string label;
    int style = 0;  // 0 line, 2 box, 3 thick line
};
void draw_legend(cv::Mat& img, int x_right, int y, const std::vector<Entry>& entries) {
    int w = 0;
    for (const Entry& e : entries) w = std::max(w, text_width(e.label, 0.45));
    const int x = x_right - w - 48, h = 20 * static_cast<int>(entries.size()) + 8;
    cv::rectangle(img, {x - 6, y - 4, w + 52, h}, cv::Scalar(255, 255, 255), cv::FILLED);
    cv::rectangle(img, {x - 6, y - 4, w + 52, h}, kGrid, 1);
    for (std::size_t i = 0; i < entries.size(); ++i) {
        const Entry& e = entries[i];
        const int yy = y + 10 + 20 * static_cast<int>(i);
        if (e.style == 2) cv::rectangle(img, {x, yy - 6, 26, 12}, e.color, cv::FILLED);
        else cv::line(img, {x, yy}, {x + 26, yy}, e.color, e.style == 3 ? 4 : 2, cv::LINE_AA);
        text(img, e.label, x + 34, yy + 5, 0.45);
    }
}

std::string png(const cv::Mat& img) {
    std::vector<unsigned char> buf;
    cv::imencode(".png", img, buf);
    return std::string(buf.begin(), buf.end());
}

// Error over time per tool, with the rule's tolerance as a light band, and a strip per tool
// under the plot: green success, red matched but failed, grey no tool reported.
std::string tip_error_plot(const EvalResult& r) {
    const ToolScore& s = r.tools;
    std::map<int, std::vector<const ToolPair*>> by_tool;
    double x0 = 1e300, x1 = -1e300, ymax = 1;
    std::vector<double> errors;
    for (const ToolPair& p : s.pairs) {
        by_tool[p.truth_id].push_back(&p);
        x0 = std::min(x0, static_cast<double>(p.frame));
        x1 = std::max(x1, static_cast<double>(p.frame));
        ymax = std::max(ymax, p.tolerance_px);
        if (p.error_px >= 0) errors.push_back(p.error_px);
    }
    // Outliers would flatten the plot: the scale covers the tolerance and the p95
    // error; larger errors are drawn clipped at the top edge as triangles.
    ymax = std::max(ymax, percentile_nearest_rank(errors, 95)) * 1.15;
    const int strips = static_cast<int>(by_tool.size());
    cv::Mat img(std::max(560 + 22 * strips, 110 + 40 * strips * 2 + 80), 1460, CV_8UC3, cv::Scalar(255, 255, 255));
    Axes a{{90, 60, 1080, 400}, x0, std::max(x1, x0 + 1), ymax};
    const std::string what = s.point == "tip" ? "Tip" : "Head";
    draw_axes(img, a, what + " error over time (" + detail::pct(s.success_rate) + " % success)",
              s.point == "tip" ? "frame" : "annotated frame (PositionIndex)", what + " error (px)");
    std::vector<Entry> legend;
    int k = 0;
    for (const auto& [id, pairs] : by_tool) {
        const cv::Scalar c = kSeries[k % 4];
        const cv::Scalar light = (c + cv::Scalar(255, 255, 255) * 1.5) / 2.5;
        cv::Point prev(-1, -1), prev_tol(-1, -1);
        std::int64_t prev_frame = -2;
        for (const ToolPair* p : pairs) {
            const cv::Point tol(a.px(p->frame), a.py(p->tolerance_px));
            if (prev_tol.x >= 0) cv::line(img, prev_tol, tol, light, 3, cv::LINE_AA);
            prev_tol = tol;
            // A line joins consecutive frames only: gaps stay gaps.
            if (p->error_px < 0 || p->frame != prev_frame + 1) prev = {-1, -1};
            prev_frame = p->frame;
            if (p->error_px < 0) continue;
            const cv::Point pt(a.px(p->frame), a.py(p->error_px));
            if (prev.x >= 0) cv::line(img, prev, pt, c, 2, cv::LINE_AA);
            if (p->error_px > ymax)
                cv::fillConvexPoly(img, std::vector<cv::Point>{{pt.x - 5, pt.y + 9}, {pt.x + 5, pt.y + 9}, {pt.x, pt.y + 1}}, kRed, cv::LINE_AA);
            prev = pt;
        }
        const std::string name = (s.point == "tip" ? "tool " : "slot ") + std::to_string(id);
        legend.push_back({c, name + " error"});
        legend.push_back({light, name + (s.point == "tip" ? " tolerance (2 x width)" : " tolerance (0.5 x SCALE)"), 3});
        // Outcome strip.
        const int y = a.area.br().y + 34 + 22 * k;
        text(img, name, 10, y + 13, 0.45);
        for (const ToolPair* p : pairs) {
            const int xa = a.px(p->frame - 0.5), xb = std::max(xa + 1, a.px(p->frame + 0.5));
            const cv::Scalar col = p->success ? kGreen : p->error_px >= 0 ? kRed : kGrey;
            cv::rectangle(img, {std::max(xa, a.area.x), y, std::min(xb, a.area.br().x) - std::max(xa, a.area.x), 16}, col, cv::FILLED);
        }
        ++k;
    }
    legend.push_back({kGreen, "success", 2});
    legend.push_back({kRed, "failed (error or axis)", 2});
    legend.push_back({kGrey, "no tool reported", 2});
    draw_legend(img, img.cols - 12, a.area.y, legend);
    return png(img);
}

// Horizontal bars, one per factor level, grouped under the factor's name, 0-100 %.
std::string factor_plot(const ToolScore& s) {
    const std::vector<LevelScore> levels = detail::ordered_levels(s.levels);
    std::vector<std::string> factors;
    for (const LevelScore& l : levels)
        if (factors.empty() || factors.back() != l.factor) factors.push_back(l.factor);
    const int bar = 30, gap = 10, head = 30;
    const int h = 100 + static_cast<int>(levels.size()) * (bar + gap) + static_cast<int>(factors.size()) * head + 50;
    cv::Mat img(h, 1000, CV_8UC3, cv::Scalar(255, 255, 255));
    const int x0 = 250, x1 = 1000 - 130;
    auto px = [&](double pct) { return x0 + static_cast<int>(std::lround(pct / 100.0 * (x1 - x0))); };
    text_c(img, "Tracking success rate per input factor", img.cols / 2, 32, 0.7, kBlack, 2);
    const int top = 60, bottom = h - 50;
    for (int v = 0; v <= 100; v += 10) {
        cv::line(img, {px(v), top}, {px(v), bottom}, v == 0 ? kAxis : kGrid, 1);
        text_c(img, std::to_string(v), px(v), bottom + 18, 0.45);
    }
    text_c(img, "success rate (%): tool-frames within the rule / all tool-frames", (x0 + x1) / 2, h - 10, 0.5);
    int y = top + 6;
    std::string factor;
    for (const LevelScore& l : levels) {
        if (l.factor != factor) {
            factor = l.factor;
            text(img, detail::factor_title(factor), 12, y + 20, 0.55, kBlack, 2);
            y += head;
        }
        const double rate = l.tool_frames ? 100.0 * l.successes / l.tool_frames : 0;
        // Red at 0 % to green at 100 %, so a glance finds the weak levels.
        const double t = rate / 100.0;
        const cv::Scalar c(60 + 20 * t, 60 + 110 * t, 215 - 155 * t);
        text(img, l.level, x0 - 12 - text_width(l.level, 0.5), y + bar / 2 + 5, 0.5);
        cv::rectangle(img, {x0, y, std::max(1, px(rate) - x0), bar}, c, cv::FILLED);
        text(img, fmt("%.1f %% (n=%d)", rate, l.tool_frames), px(rate) + 6, y + bar / 2 + 5, 0.45);
        y += bar + gap;
    }
    return png(img);
}

// Rows performed, columns recognized; colour = share of the row, text = trials.
std::string confusion_plot(const GestureScore& g) {
    const int cell = 92, left = 190, top = 130;
    cv::Mat img(top + cell * kGestureCount + 60, left + cell * kGestureCount + 120, CV_8UC3,
                cv::Scalar(255, 255, 255));
    text_c(img, "Gesture confusion (trials): performed vs recognized", img.cols / 2, 30, 0.7, kBlack, 2);
    text_c(img, "recognized", left + cell * kGestureCount / 2, 62, 0.55);
    text_v(img, "performed", 18, top + cell * kGestureCount / 2);
    auto two_lines = [&](const std::string& s, int x, int y, bool centre) {
        const std::size_t sp = s.find(' ');
        const std::string a = sp == std::string::npos ? s : s.substr(0, sp);
        const std::string b = sp == std::string::npos ? "" : s.substr(sp + 1);
        if (centre) {
            text_c(img, a, x, b.empty() ? y + 9 : y, 0.45);
            if (!b.empty()) text_c(img, b, x, y + 18, 0.45);
        } else {
            text(img, a, x - text_width(a, 0.45), b.empty() ? y + 5 : y - 4, 0.45);
            if (!b.empty()) text(img, b, x - text_width(b, 0.45), y + 14, 0.45);
        }
    };
    for (int c = 0; c < kGestureCount; ++c) two_lines(gesture_title(c), left + c * cell + cell / 2, top - 34, true);
    text_c(img, "rate", left + cell * kGestureCount + 60, top - 16, 0.5, kBlack, 2);
    for (int p = 0; p < kGestureCount; ++p) {
        int total = 0;
        for (int c = 0; c < kGestureCount; ++c) total += g.counts[p][c];
        const int y = top + p * cell;
        two_lines(gesture_title(p), left - 10, y + cell / 2, false);
        for (int c = 0; c < kGestureCount; ++c) {
            const double share = total ? static_cast<double>(g.counts[p][c]) / total : 0;
            // White to dark blue; the diagonal in green tones so hits read as hits.
            const cv::Scalar col = p == c ? cv::Scalar(255 - 175 * share, 255 - 85 * share, 255 - 195 * share)
                                          : cv::Scalar(255 - 55 * share, 255 - 165 * share, 255 - 195 * share);
            const cv::Rect r(left + c * cell, y, cell, cell);
            cv::rectangle(img, r, col, cv::FILLED);
            cv::rectangle(img, r, kGrid, 1);
            if (total > 0)
                text_c(img, std::to_string(g.counts[p][c]), r.x + cell / 2, r.y + cell / 2 + 7, 0.6,
                       share > 0.55 ? cv::Scalar(255, 255, 255) : kBlack, share > 0 ? 2 : 1);
        }
        const auto rate = g.rate(p);
        text_c(img, rate ? fmt("%.0f %%", 100 * *rate) : "-", left + cell * kGestureCount + 60, y + cell / 2 + 6, 0.55);
    }
    text(img, "cell colour: share of the performed row; green diagonal = recognized correctly", left,
         img.rows - 20, 0.45, kAxis);
    return png(img);
}

// Corner error over time, with the GOOD/OK/FAIL class as a strip per region.
std::string region_plot(const RegionScore& g) {
    std::map<int, std::vector<const RegionFrameScore*>> by_region;
    double x0 = 1e300, x1 = -1e300, ymax = 1;
    std::vector<double> errors;
    for (const RegionFrameScore& f : g.frames) {
        by_region[f.truth_id].push_back(&f);
        x0 = std::min(x0, static_cast<double>(f.frame));
        x1 = std::max(x1, static_cast<double>(f.frame));
        if (f.match.corner_error_px) errors.push_back(*f.match.corner_error_px);
    }
    ymax = std::max(ymax, percentile_nearest_rank(errors, 95)) * 1.15;
    const int strips = static_cast<int>(by_region.size());
    cv::Mat img(560 + 22 * strips, 1460, CV_8UC3, cv::Scalar(255, 255, 255));
    Axes a{{90, 60, 1080, 400}, x0, std::max(x1, x0 + 1), ymax};
    draw_axes(img, a, fmt("Region tracking: GOOD %d, OK %d, FAIL %d", g.good, g.ok, g.fail), "frame",
              "mean corner error (px)");
    std::vector<Entry> legend;
    int k = 0;
    for (const auto& [id, frames] : by_region) {
        const cv::Scalar c = kSeries[k % 4];
        cv::Point prev(-1, -1);
        for (const RegionFrameScore* f : frames) {
            if (!f->match.corner_error_px) {
                prev = {-1, -1};
                continue;
            }
            const cv::Point pt(a.px(f->frame), a.py(*f->match.corner_error_px));
            if (prev.x >= 0) cv::line(img, prev, pt, c, 2, cv::LINE_AA);
            prev = pt;
        }
        legend.push_back({c, "region " + std::to_string(id) + " corner error"});
        const int y = a.area.br().y + 34 + 22 * k;
        text(img, "region " + std::to_string(id), 10, y + 13, 0.45);
        for (const RegionFrameScore* f : frames) {
            const int xa = a.px(f->frame - 0.5), xb = std::max(xa + 1, a.px(f->frame + 0.5));
            const cv::Scalar col = f->match.cls == RegionClass::kGood ? kGreen
                                   : f->match.cls == RegionClass::kOk ? kAmber : kRed;
            cv::rectangle(img, {std::max(xa, a.area.x), y, std::min(xb, a.area.br().x) - std::max(xa, a.area.x), 16}, col, cv::FILLED);
        }
        ++k;
    }
    legend.push_back({kGreen, "GOOD", 2});
    legend.push_back({kAmber, "OK", 2});
    legend.push_back({kRed, "FAIL", 2});
    draw_legend(img, img.cols - 12, a.area.y, legend);
    return png(img);
}

}  // namespace

std::vector<std::pair<std::string, std::string>> render_plots(const EvalResult& r) {
    std::vector<std::pair<std::string, std::string>> out;
    if (r.tools.tool_frames > 0) out.emplace_back("tip_error.png", tip_error_plot(r));
    if (!r.tools.levels.empty()) out.emplace_back("success_by_factor.png", factor_plot(r.tools));
    if (r.gestures.present) out.emplace_back("gesture_confusion.png", confusion_plot(r.gestures));
    if (r.regions.present && !r.regions.frames.empty()) out.emplace_back("regions.png", region_plot(r.regions));
    return out;
}

}  // namespace endotower::eval
