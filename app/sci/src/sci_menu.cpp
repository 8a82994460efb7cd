#include "endotower/sci/sci_menu.hpp"

#include <algorithm>
#include <cmath>

namespace endotower::sci {

namespace {

constexpr float kPi = 3.14159265358979f;

SciItem button(std::string_view label, SciAction a, float x, float y, float w, float h) {
    SciItem i;
    i.label = label;
    i.action = a;
    i.x = x, i.y = y, i.width = w, i.height = h;
    return i;
}

SciItem sector(std::string_view label, SciAction a, float cx, float cy, float r0, float r1,
               float start, float end) {
    SciItem i;
    i.label = label;
    i.action = a;
    i.sector = true;
    i.cx = cx, i.cy = cy, i.r_inner = r0, i.r_outer = r1, i.start_deg = start, i.end_deg = end;
    return i;
}

SciItem with(SciItem i, MenuId target) {
    i.target = target;
    return i;
}
SciItem with(SciItem i, SciModality m) {
    i.modality = m;
    return i;
}

void add(SciMenu& m, const SciItem& i) {
    if (m.count < SciMenu::kMaxItems) m.items[m.count++] = i;
}

// A column of buttons from the top, `left` and `width` as fractions of the frame width.
struct Column {
    float left, width, top, height, pitch;
    SciItem at(int row, std::string_view label, SciAction a) const {
        return button(label, a, left, top + static_cast<float>(row) * pitch, width, height);
    }
};

}  // namespace

bool parse_sci_layout(std::string_view t, SciLayout& out) {
    if (t == "buttons")
        out = SciLayout::kButtons;
    else if (t == "ring")
        out = SciLayout::kRing;
    else if (t == "three_level")
        out = SciLayout::kThreeLevel;
    else
        return false;
    return true;
}

std::string_view to_string(SciLayout l) {
    switch (l) {
        case SciLayout::kButtons:
            return "buttons";
        case SciLayout::kRing:
            return "ring";
        case SciLayout::kThreeLevel:
            return "three_level";
    }
    return "?";
}

std::string_view to_string(SciModality m) {
    switch (m) {
        case SciModality::kCt:
            return "ct";
        case SciModality::kXray:
            return "xray";
        case SciModality::kMri:
            return "mri";
    }
    return "?";
}

std::string_view to_string(MenuId m) {
    switch (m) {
        case MenuId::kMain:
            return "main";
        case MenuId::kQuadrant:
            return "quadrant";
        case MenuId::kImages:
            return "preoperative_images";
        case MenuId::kEffects:
            return "3d_effects";
        case MenuId::kViewer:
            return "viewer";
        case MenuId::kRecord:
            return "patient_record";
        case MenuId::kBox:
            return "image_box";
        case MenuId::kSuture:
            return "suture";
    }
    return "?";
}

bool SciMenu::near(std::size_t k, float x, float y, float m) const {
    if (k >= count) return false;
    const SciItem& i = items[k];
    if (!i.sector)
        return x >= i.x - m && x < i.x + i.width + m && y >= i.y - m && y < i.y + i.height + m;
    const float dx = x - i.cx, dy = y - i.cy, r = std::hypot(dx, dy);
    if (r < i.r_inner - m || r >= i.r_outer + m) return false;
    const float grow = m / std::max(r, 1.0f) * 180.0f / kPi;  // the margin as an arc, degrees
    float a = std::atan2(dy, dx) * 180.0f / kPi;              // clockwise on screen (y down)
    while (a < i.start_deg - grow) a += 360.0f;
    while (a >= i.start_deg - grow + 360.0f) a -= 360.0f;
    return a < i.end_deg + grow;
}

int SciMenu::hit(float x, float y, float margin) const {
    for (std::size_t k = 0; k < count; ++k)
        if (near(k, x, y, margin)) return static_cast<int>(k);
    return -1;
}

SciMenuTable build_menus(SciLayout layout, int width, int height) {
    SciMenuTable t{};
    for (std::size_t k = 0; k < kMenuCount; ++k) t[k].id = static_cast<MenuId>(k);
    const float w = static_cast<float>(width), h = static_cast<float>(height);
    const float cx = w / 2, cy = h / 2;
    auto menu = [&t](MenuId id) -> SciMenu& { return t[static_cast<std::size_t>(id)]; };

    // Fig. 3.34a: four quadrants around a free middle, reaching the frame's corners.
    {
        const float r0 = 0.22f * h, r1 = std::hypot(w, h);
        SciMenu& q = menu(MenuId::kQuadrant);
        add(q,
            with(sector("Open CT", SciAction::kView, cx, cy, r0, r1, -135, -45), SciModality::kCt));
        add(q, with(sector("Open X-Ray", SciAction::kView, cx, cy, r0, r1, -45, 45),
                    SciModality::kXray));
        add(q,
            with(sector("Open MRI", SciAction::kView, cx, cy, r0, r1, 45, 135), SciModality::kMri));
        add(q, sector("Exit", SciAction::kExit, cx, cy, r0, r1, 135, 225));
    }

    if (layout == SciLayout::kRing) {
        // Fig. 3.34b: a ring inside the field of view's edge (radius ~0.49 h), leaving
        // the outer 0.09 h free: near the dark rim the trackers lose the tip (the
        // likelihood tracker beyond ~0.37 h in the scene suites). Fig. 3.35's sub-ring
        // just inside it.
        const float r0 = 0.30f * h, r1 = 0.40f * h, s0 = 0.19f * h, s1 = 0.28f * h;
        SciMenu& m = menu(MenuId::kMain);
        add(m, with(sector("CT", SciAction::kView, cx, cy, r0, r1, -135, -45), SciModality::kCt));
        add(m,
            with(sector("X-RAY", SciAction::kView, cx, cy, r0, r1, -45, 45), SciModality::kXray));
        add(m, with(sector("MRI", SciAction::kView, cx, cy, r0, r1, 45, 135), SciModality::kMri));
        add(m, sector("EXIT", SciAction::kExit, cx, cy, r0, r1, 135, 225));
        SciMenu& v = menu(MenuId::kViewer);
        add(v, sector("Previous", SciAction::kPrevious, cx, cy, s0, s1, 150, 210));
        add(v, sector("Next", SciAction::kNext, cx, cy, s0, s1, -30, 30));
        add(v, sector("Main menu", SciAction::kReturn, cx, cy, s0, s1, -120, -60));
        return t;
    }
    if (layout == SciLayout::kButtons) {
        // Fig. 3.32: a column at the right edge, clear of the tools' usual paths.
        const Column c{0.78f * w, 0.20f * w, 0.08f * h, 0.10f * h, 0.13f * h};
        SciMenu& m = menu(MenuId::kMain);
        add(m, with(c.at(0, "Display CT", SciAction::kView), SciModality::kCt));
        add(m, with(c.at(1, "Display X-Ray", SciAction::kView), SciModality::kXray));
        add(m, with(c.at(2, "Display MRI", SciAction::kView), SciModality::kMri));
        add(m, c.at(3, "Exit", SciAction::kExit));
        SciMenu& v = menu(MenuId::kViewer);
        add(v, c.at(0, "Previous", SciAction::kPrevious));
        add(v, c.at(1, "Next", SciAction::kNext));
        add(v, c.at(2, "Return", SciAction::kReturn));
        add(v, c.at(3, "Exit", SciAction::kExit));
        return t;
    }
    // Fig. 4.33/4.34: a column at the left edge; the upper right shows the images.
    const Column c{0.03f * w, 0.26f * w, 0.10f * h, 0.09f * h, 0.12f * h};
    SciMenu& m = menu(MenuId::kMain);
    add(m, with(c.at(0, "Preoperative images", SciAction::kSubmenu), MenuId::kImages));
    add(m, c.at(1, "Patient record", SciAction::kPatientRecord));
    add(m, with(c.at(2, "3-D effects", SciAction::kSubmenu), MenuId::kEffects));
    add(m, c.at(3, "Exit", SciAction::kExit));
    SciMenu& im = menu(MenuId::kImages);
    add(im, with(c.at(0, "CT", SciAction::kView), SciModality::kCt));
    add(im, with(c.at(1, "MRI", SciAction::kView), SciModality::kMri));
    add(im, with(c.at(2, "X-ray", SciAction::kView), SciModality::kXray));
    add(im, c.at(3, "Return", SciAction::kReturn));
    SciMenu& fx = menu(MenuId::kEffects);
    add(fx, c.at(0, "Image box", SciAction::kImageBox));
    add(fx, c.at(1, "Suture manipulation", SciAction::kSuture));
    add(fx, c.at(2, "Return", SciAction::kReturn));
    SciMenu& v = menu(MenuId::kViewer);
    add(v, c.at(0, "Previous", SciAction::kPrevious));
    add(v, c.at(1, "Next", SciAction::kNext));
    add(v, c.at(2, "Return", SciAction::kReturn));
    add(v, c.at(3, "Exit", SciAction::kExit));
    for (MenuId page : {MenuId::kRecord, MenuId::kBox, MenuId::kSuture}) {
        add(menu(page), c.at(0, "Return", SciAction::kReturn));
        add(menu(page), c.at(1, "Exit", SciAction::kExit));
    }
    return t;
}

}  // namespace endotower::sci
