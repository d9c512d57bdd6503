#pragma once
// The single-camera scenes the tests and the docs use: one per condition a
// real photo brings (shadows, low contrast, white or dark cloth, prints, a
// reverse side, sequins, markers, a rotated camera, a rectangle) and one per
// refusal. Each comes with the flags `drape measure --top` gets.
#include "synthetic_photo.hpp"

#include <string>
#include <vector>

namespace synth_photo {

struct Case {
    std::string name;
    Scene scene;
    std::vector<std::string> flags; ///< besides --top PHOTO
    std::string refusal;            ///< expected refusal check ("" = measured)
    double area_tolerance = 0.01;   ///< relative area error allowed where the geometry is declared
};

inline std::vector<Case> cases()
{
    std::vector<Case> v;
    const std::vector<std::string> base{"--disc", "180mm", "--specimen", "300mm"};
    auto with = [&](std::vector<std::string> extra) {
        auto f = base;
        f.insert(f.end(), extra.begin(), extra.end());
        return f;
    };
    Scene s;
    v.push_back({"plain", s, with({"--camera-height", "700mm"}), ""});
    v.push_back({"plain-unknown-height", s, with({}), ""});
    {
        Scene t = s;
        t.rig_shadow = true;
        v.push_back({"rig-shadow", t, with({"--camera-height", "700mm"}), ""});
    }
    {
        Scene t = s;
        t.cloth_bgr = {200, 196, 236}; // pastel pink
        t.background_bgr = {208, 232, 242}; // cream
        t.ambient = 0.75;
        v.push_back({"pastel-on-cream", t, with({"--camera-height", "700mm"}), ""});
    }
    {
        Scene t = s;
        t.cloth_bgr = {246, 246, 244};
        t.background_bgr = {196, 198, 200};
        t.ambient = 0.6;
        v.push_back({"white-on-light", t, with({"--camera-height", "700mm"}), ""});
    }
    {
        Scene t = s;
        t.cloth_bgr = {38, 36, 40};
        t.background_bgr = {78, 80, 82};
        t.background_texture = true;
        v.push_back({"dark-on-dark", t, with({"--camera-height", "700mm"}), ""});
    }
    {
        Scene t = s;
        t.cloth_bgr = {120, 50, 35}; // navy base
        t.print = true;
        v.push_back({"print", t, with({"--camera-height", "700mm"}), ""});
        // One of the print's colours is the background's: where such a patch
        // lies on the hem, nothing in the colours tells it from the background.
        // A known limit: under-counted by up to ~4 % of the area (the overlay
        // shows the bites); a contrasting background or --mask is the way out.
        t.print_white = true;
        v.push_back({"print-with-background-colour", t, with({"--camera-height", "700mm"}), "", 0.04});
    }
    {
        Scene t = s;
        t.cloth_bgr = {50, 40, 175};
        t.reverse_bgr = {200, 226, 236};
        t.background_bgr = {150, 150, 152};
        t.background_texture = true;
        v.push_back({"reverse-side", t, with({"--camera-height", "700mm"}), ""});
    }
    {
        Scene t = s;
        t.cloth_bgr = {70, 150, 190}; // gold
        t.sequins = true;
        t.background_bgr = {232, 232, 232};
        v.push_back({"sequins", t, with({"--camera-height", "700mm"}), ""});
    }
    {
        Scene t = s;
        t.clamp_bgr = {200, 200, 205}; // an upper disc of light metal
        v.push_back({"upper-disc", t, with({"--camera-height", "700mm"}), ""});
    }
    {
        Scene t = s;
        t.markers = true;
        t.markers_z = -0.12; // printed sheet on the floor of a 120 mm stand
        t.H = 0.60;
        t.f = 1000;
        v.push_back({"markers-floor", t, with({"--scale", "markers", "--marker-size", "50mm", "--reference-height", "-120mm"}), ""});
    }
    {
        Scene t = s;
        t.markers = true;
        t.markers_z = -0.12;
        t.roll_deg = 30;
        t.tilt_deg = 4;
        t.offset = {0.03, -0.02};
        t.H = 0.65;
        v.push_back({"rotated-camera", t, with({"--scale", "markers", "--marker-size", "50mm", "--reference-height", "-120mm"}), ""});
    }
    {
        Scene t = s;
        t.chessboard = true;
        t.markers_z = -0.12;
        t.H = 0.65;
        t.f = 1000;
        v.push_back({"chessboard-floor", t, with({"--scale", "chessboard", "--board", "6x4", "--square", "25mm", "--reference-height", "-120mm"}), ""});
    }
    {
        Scene t = s;
        t.rectangle = true;
        t.width = 0.30;
        t.length = 0.40;
        t.angle = 20 * kPi / 180;
        t.H = 0.80;
        t.k0 = 0.5;
        t.k1 = 0.2;
        t.nodes = 4;
        v.push_back({"rectangle", t, {"--disc", "180mm", "--specimen", "300x400mm", "--specimen-angle", "20", "--camera-height", "800mm"}, ""});
    }
    {
        // A real failure: a camera rig's shadow nearly as dark as a grey cloth
        // joined it (D 54.8 % where the photo's authors measured 31.4 %).
        Scene t = s;
        t.cloth_bgr = {118, 118, 120};
        t.background_bgr = {214, 214, 212};
        t.ambient = 0.7;
        t.rig_shadow = true;
        t.shadow_depth = 0.40; // shadowed floor 128: 4-8 L* units from the cloth's lit faces
        v.push_back({"grey-cloth-rig-shadow", t, with({"--camera-height", "700mm"}), ""});
        // Darker still (shadowed floor 113, the cloth's lit faces 118): refused, never
        // measured wrong (0.42-0.47 were tried: all refused as this one).
        t.shadow_depth = 0.47;
        v.push_back({"refused-grey-cloth-darker-rig-shadow", t, with({"--camera-height", "700mm"}), "low-contrast"});
    }
    {
        // A real failure: half of a white knit on a cream floor was missed (D 30.4 %
        // where the authors measured 49.0 %): its lit faces are nearly the floor's colour.
        Scene t = s;
        t.cloth_bgr = {238, 241, 242};
        t.background_bgr = {204, 228, 240};
        t.ambient = 0.8;
        v.push_back({"white-knit-on-cream", t, with({"--camera-height", "700mm"}), ""});
        // Off-white, its lit faces the floor's colour: refused (blue 218-226 were
        // tried between this and the white knit: all measured within 0.5 point).
        t.cloth_bgr = {214, 234, 242};
        t.ambient = 0.85;
        v.push_back({"refused-off-white-knit-on-cream", t, with({"--camera-height", "700mm"}), "low-contrast"});
    }
    {
        Scene t = s;
        t.cloth_bgr = {40, 40, 44};
        t.background_bgr = {200, 202, 204};
        t.rig_shadow = true;
        t.shadow_depth = 0.8; // the rig's shadow is as dark as the cloth
        v.push_back({"refused-shadow-as-dark-as-cloth", t, with({"--camera-height", "700mm"}), "low-contrast"});
    }
    {
        Scene t = s;
        v.push_back({"refused-wrong-specimen", t, {"--disc", "180mm", "--specimen", "240mm", "--camera-height", "700mm"}, "beyond-specimen"});
    }
    {
        Scene t = s;
        v.push_back({"refused-specimen-too-small", t, {"--disc", "180mm", "--specimen", "220mm", "--camera-height", "700mm"}, "search-limit"});
    }
    {
        Scene t = s;
        t.offset = {0.20, 0.0}; // the drape runs off the photo's left edge
        t.H = 0.50;
        v.push_back({"refused-off-photo", t, with({"--camera-height", "500mm"}), "border"});
    }
    {
        Scene t = s;
        t.cloth_bgr = {150, 150, 152};
        t.background_bgr = {150, 150, 152};
        t.ambient = 1.0;
        v.push_back({"refused-no-disc-rim", t, with({"--camera-height", "700mm"}), "disc-not-found"});
        // With the disc's position given, the next check: cloth like the background.
        v.push_back({"refused-no-contrast", t, with({"--camera-height", "700mm", "--disc-px", "639.5,479.5,141.4"}), "low-contrast"});
    }
    {
        Scene t = s;
        v.push_back({"refused-no-markers", t, {"--disc", "180mm", "--specimen", "300mm", "--scale", "markers", "--marker-size", "50mm"}, "markers-not-found"});
    }
    return v;
}

} // namespace synth_photo
