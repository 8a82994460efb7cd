#include "endotower/sci/sci_scene.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>

namespace endotower::sci {

namespace {

constexpr hal::Rgba8 kItem{30, 60, 110, 130}, kItemBorder{200, 220, 255, 200};
constexpr hal::Rgba8 kHighlight{250, 190, 40, 190}, kText{255, 255, 255, 255};
constexpr hal::Rgba8 kPanel{20, 20, 30, 170}, kArea{255, 255, 255, 60};

hal::SceneText text(std::string_view s, float x, float y, float size, hal::SceneText::Align a) {
    hal::SceneText t;
    set_text(t, s);
    t.x = x, t.y = y, t.size_px = size, t.align = a, t.colour = kText;
    return t;
}

void menu_items(const SciMachine& m, const SciSceneInput& in, hal::OverlayScene& s) {
    const SciMenu& menu = m.menu();
    const float size = std::max(12.0f, static_cast<float>(in.height) / 27.0f);
    for (std::size_t k = 0; k < menu.count; ++k) {
        const SciItem& i = menu.items[k];
        const bool lit = static_cast<int>(k) == m.highlighted();
        const hal::Rgba8 fill = lit ? kHighlight : kItem;
        if (i.sector) {
            s.sectors.add(
                {i.cx, i.cy, i.r_inner, i.r_outer, i.start_deg, i.end_deg, 2, fill, kItemBorder});
            // The label sits in the sector's middle, clamped into the frame (quadrants
            // reach the corners).
            const float a = (i.start_deg + i.end_deg) / 2 * 3.14159265f / 180.0f;
            const float r = std::min(i.r_outer, i.r_inner + 0.18f * static_cast<float>(in.height));
            const float r_mid = i.r_outer - i.r_inner < 0.2f * static_cast<float>(in.height)
                                    ? (i.r_inner + i.r_outer) / 2
                                    : (i.r_inner + r) / 2 + 0.05f * static_cast<float>(in.height);
            const float x = std::clamp(i.cx + r_mid * std::cos(a), size * 3,
                                       static_cast<float>(in.width) - size * 3);
            const float y =
                std::clamp(i.cy + r_mid * std::sin(a), size, static_cast<float>(in.height) - size);
            s.texts.add(text(i.label, x, y, size, hal::SceneText::Align::kCentre));
        } else {
            s.quads.add({i.x, i.y, i.width, i.height, i.height / 5, 2, fill, kItemBorder});
            s.texts.add(text(i.label, i.x + i.width / 2, i.y + i.height / 2, size,
                             hal::SceneText::Align::kCentre));
        }
    }
}

void viewer(const SciMachine& m, const SciParams& p, const SciSceneInput& in,
            hal::OverlayScene& s) {
    const float w = static_cast<float>(in.width), h = static_cast<float>(in.height);
    // Three-level: the upper-right window (fig. 4.34b); buttons: left of the column;
    // ring: inside the sub-ring.
    float x = 0.62f * w, y = 0.04f * h, iw = 0.35f * w, ih = 0.40f * h;
    if (p.layout == SciLayout::kButtons) x = 0.40f * w, y = 0.08f * h;
    if (p.layout == SciLayout::kRing) iw = ih = 0.40f * h, x = w / 2 - iw / 2, y = h / 2 - ih / 2;
    const int n = p.image_counts[static_cast<std::size_t>(m.modality())];
    char caption[96];
    std::snprintf(caption, sizeof caption, "%s %d/%d %.*s",
                  m.modality() == SciModality::kCt    ? "CT"
                  : m.modality() == SciModality::kMri ? "MRI"
                                                      : "X-ray",
                  n > 0 ? m.image_index() + 1 : 0, n,
                  static_cast<int>(std::min<std::size_t>(in.image_name.size(), 60)),
                  in.image_name.data());
    s.quads.add({x - 4, y - 4, iw + 8, ih + 8 + h / 20, 6, 0, kPanel, {}});
    if (in.image_slot >= 0)
        s.images.add({in.image_slot, x, y, iw, ih, 1});
    else
        s.texts.add(
            text(n == 0 ? std::string_view("no images in the media folder") : in.image_message,
                 x + iw / 2, y + ih / 2, h / 30, hal::SceneText::Align::kCentre));
    s.texts.add(text(caption, x, y + ih + 6, h / 30, hal::SceneText::Align::kTopLeft));
}

void record(const SciSceneInput& in, hal::OverlayScene& s) {
    if (!in.has_tip) return;
    // Fig. 4.35: the record sticks to the tip, which stays at its centre.
    const float h = static_cast<float>(in.height), line = h / 28;
    const std::size_t n = std::min<std::size_t>(in.record_lines.size(), 12);
    const float pw = 0.36f * static_cast<float>(in.width), ph = line * (static_cast<float>(n) + 1);
    const float x = in.tip_x - pw / 2, y = in.tip_y - ph / 2;
    s.quads.add({x, y, pw, ph, 8, 2, {245, 245, 235, 200}, {60, 60, 60, 220}});
    for (std::size_t k = 0; k < n; ++k) {
        hal::SceneText t =
            text(in.record_lines[k], x + line / 2, y + line / 2 + line * static_cast<float>(k),
                 line * 0.9f, hal::SceneText::Align::kTopLeft);
        t.colour = {10, 10, 20, 255};
        s.texts.add(t);
    }
}

void box(const SciMachine& m, const SciSceneInput& in, hal::OverlayScene& s) {
    if (!s.camera.valid()) {
        s.texts.add(text("Image box: no calibrated camera (board: calibration)",
                         static_cast<float>(in.width) / 2, static_cast<float>(in.height) / 2,
                         static_cast<float>(in.height) / 24, hal::SceneText::Align::kCentre));
        return;
    }
    hal::SceneBox b;
    b.camera_from_model = m.box().camera_from_model();
    b.size_mm = static_cast<float>(ImageBox::kEdgeMm);
    for (int f = 0; f < 6; ++f) b.faces[f] = {static_cast<std::uint8_t>(120 + 20 * f), 90, 80, 150};
    const int lit = m.state() == SciState::kGrabbed ? -2 : m.box_face();
    for (int f = 0; f < 6; ++f)
        if (f == lit || lit == -2) b.faces[f] = kHighlight;
    s.boxes.add(b);
    // The target marker: three 10 mm axes (fig. 4.42).
    const Vec3d t = m.box_target_mm();
    const hal::Rgba8 axes[3] = {{255, 60, 60, 230}, {60, 255, 60, 230}, {60, 120, 255, 230}};
    for (int a = 0; a < 3; ++a) {
        hal::SceneLine3 l;
        l.points[0] = {static_cast<float>(t.x), static_cast<float>(t.y), static_cast<float>(t.z)};
        l.points[1] = l.points[0];
        (a == 0 ? l.points[1].x : a == 1 ? l.points[1].y : l.points[1].z) += 10;
        l.count = 2;
        l.width_px = 3;
        l.colour = axes[a];
        s.lines3.add(l);
    }
}

void suture(const SciMachine& m, const SciSceneInput& in, hal::OverlayScene& s) {
    if (!m.suture_started()) return;
    const auto& nodes = m.suture().nodes();
    const hal::Rgba8 colour{240, 240, 120, 255};
    if (in.suture_in_mm) {
        hal::SceneLine3 l;
        for (const Vec3d& v : nodes)
            l.points[l.count++] = {static_cast<float>(v.x), static_cast<float>(v.y),
                                   static_cast<float>(v.z)};
        l.width_px = 3, l.colour = colour;
        s.lines3.add(l);
    } else {
        hal::SceneLine l;
        for (const Vec3d& v : nodes)
            l.points[l.count++] = {static_cast<float>(v.x), static_cast<float>(v.y)};
        l.width_px = 3, l.colour = colour;
        s.lines.add(l);
    }
}

}  // namespace

void set_text(hal::SceneText& t, std::string_view s) {
    std::size_t n = std::min(s.size(), t.utf8.size() - 1);
    while (n > 0 && n < s.size() && (static_cast<unsigned char>(s[n]) & 0xC0) == 0x80) --n;
    std::copy_n(s.data(), n, t.utf8.data());
    t.utf8[n] = 0;
}

void build_sci_scene(const SciMachine& m, const SciParams& p, const SciSceneInput& in,
                     hal::OverlayScene& s) {
    const hal::SceneCamera camera = s.camera;
    s.clear();
    s.camera = camera;
    if (m.state() == SciState::kActivating) {
        const float x0 = m.activation_x0(), y0 = m.activation_y0();
        s.quads.add(
            {x0, y0, m.activation_x1() - x0, static_cast<float>(in.height) - y0, 0, 0, kArea, {}});
        s.discs.add({in.gesture_x, in.gesture_y, 0.03f * static_cast<float>(in.height),
                     0.04f * static_cast<float>(in.height),
                     static_cast<float>(360 * m.activation_fraction()), kHighlight});
        return;
    }
    if (!m.active()) return;
    switch (m.menu().id) {
        case MenuId::kViewer:
            viewer(m, p, in, s);
            break;
        case MenuId::kRecord:
            record(in, s);
            break;
        case MenuId::kBox:
            box(m, in, s);
            break;
        case MenuId::kSuture:
            suture(m, in, s);
            break;
        default:
            break;
    }
    menu_items(m, in, s);
    if (m.state() == SciState::kConfirm) {
        const float w = static_cast<float>(in.width), h = static_cast<float>(in.height);
        s.quads.add({0.3f * w, 0.42f * h, 0.4f * w, 0.16f * h, 10, 2, kPanel, kHighlight});
        s.texts.add(text("Confirm: loop the tool within 2 s", w / 2, h / 2, h / 24,
                         hal::SceneText::Align::kCentre));
    }
    if (in.has_tip && m.dwell_fraction() > 0) {
        const float h = static_cast<float>(in.height);
        s.discs.add({in.tip_x, in.tip_y, 0.035f * h, 0.045f * h,
                     static_cast<float>(360 * m.dwell_fraction()), kHighlight});
    }
}

}  // namespace endotower::sci
