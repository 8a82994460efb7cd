// build_sci_scene: what the SCI shows for the machine's state, as an OverlayScene
// (fixed capacity, no allocation). Inactive: nothing; activating: the shaded
// activation area (fig. 3.31) and a progress arc at the scissors. Active: the menu's
// items (semi-transparent; the highlighted one bright) with their labels, a dwell arc
// at the tip, and the function page: the image viewer's picture (renderer image slot
// `image_slot`, -1 = not loaded: its name and `image_message` instead), the patient
// record centred on the tip (fig. 4.35), the image box and its target marker (needs
// a valid scene camera), the suture thread; a confirmation prompt while confirming.
// `tip_*`: the cursor (tools[0]); `image_name` and `record_lines` are borrowed.
#pragma once

#include <span>
#include <string_view>

#include "endotower/hal/overlay_scene.hpp"
#include "endotower/sci/sci_machine.hpp"

namespace endotower::sci {

struct SciSceneInput {
    bool has_tip = false;
    float tip_x = 0, tip_y = 0;
    float gesture_x = 0, gesture_y = 0;
    int width = 0, height = 0;
    int image_slot = -1;
    std::string_view image_name, image_message;
    std::span<const std::string_view> record_lines;
    bool suture_in_mm = false;
};

void build_sci_scene(const SciMachine& m, const SciParams& p, const SciSceneInput& in,
                     hal::OverlayScene& scene);

// Copies `text` into a SceneText's fixed buffer (truncated at a UTF-8 boundary).
void set_text(hal::SceneText& t, std::string_view text);

}  // namespace endotower::sci
