// SciMenu: the surgeon-computer interface's menus, their items and where they sit on
// the video frame, for the three layouts of the book:
//   kButtons     overlaid function buttons (fig. 3.32): Display CT / X-Ray / MRI, Exit,
//                in a column at the right edge;
//   kRing        a ring around the field of view (fig. 3.34b; radii 0.30-0.40 x the
//                frame height, the sub-ring 0.19-0.28) split into CT,
//                X-RAY, MRI, EXIT; an image page adds an inner sub-ring Previous, Next,
//                Main menu (fig. 3.35);
//   kThreeLevel  main menu, submenus and function pages (fig. 4.33/4.34): Main =
//                Preoperative images, Patient record, 3-D effects, Exit; Preoperative
//                images = CT, MRI, X-ray, Return; 3-D effects = Image box, Suture
//                manipulation, Return; every function page has Return and Exit.
// Every layout also has the quadrant menu the cross gesture opens (fig. 3.34a): Open
// CT (top), Open X-Ray (right), Open MRI (bottom), Exit (left), the middle left free.
//
// Geometry is in pixels of the frame (x right, y down): an item is a rectangle or an
// annular sector (degrees, 0 = +x, clockwise on screen, as hal::SceneSector).
// build_menus() fills a fixed table for one frame size; nothing allocates.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <string_view>

namespace endotower::sci {

enum class SciLayout : std::uint8_t { kButtons, kRing, kThreeLevel };
bool parse_sci_layout(std::string_view text, SciLayout& out);  // "buttons" | "ring" | "three_level"
std::string_view to_string(SciLayout layout);

enum class SciModality : std::uint8_t { kCt, kXray, kMri };
constexpr std::size_t kModalityCount = 3;
std::string_view to_string(SciModality m);  // "ct" | "xray" | "mri": the media sub-folders

enum class MenuId : std::uint8_t {
    kMain,
    kQuadrant,
    kImages,
    kEffects,
    kViewer,
    kRecord,
    kBox,
    kSuture
};
constexpr std::size_t kMenuCount = 8;
// The trace's "menu": main, quadrant, preoperative_images, 3d_effects, viewer,
// patient_record, image_box, suture.
std::string_view to_string(MenuId m);

enum class SciAction : std::uint8_t {
    kSubmenu,  // opens `target`
    kReturn,   // back to the menu this one was opened from
    kMain,     // back to the main menu
    kExit,     // deactivates the interface
    kView,     // image viewer of `modality`
    kPrevious,
    kNext,
    kPatientRecord,
    kImageBox,
    kSuture,
};

struct SciItem {
    std::string_view label;
    SciAction action = SciAction::kReturn;
    MenuId target = MenuId::kMain;
    SciModality modality = SciModality::kCt;
    bool sector = false;
    float x = 0, y = 0, width = 0, height = 0;                                   // a rectangle
    float cx = 0, cy = 0, r_inner = 0, r_outer = 0, start_deg = 0, end_deg = 0;  // a sector
};

struct SciMenu {
    static constexpr std::size_t kMaxItems = 6;
    MenuId id = MenuId::kMain;
    std::array<SciItem, kMaxItems> items{};
    std::size_t count = 0;
    // The index of the first item under (x, y), each grown by `margin` px (near), or -1.
    int hit(float x, float y, float margin = 0) const;
    // Whether (x, y) lies on item k grown by `margin` px on every side (a sector: radially,
    // and by that arc at the point's radius).
    bool near(std::size_t k, float x, float y, float margin) const;
};

using SciMenuTable = std::array<SciMenu, kMenuCount>;
SciMenuTable build_menus(SciLayout layout, int width, int height);

}  // namespace endotower::sci
