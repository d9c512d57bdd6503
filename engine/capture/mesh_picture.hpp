#pragma once
// A picture of meshes for a person: the front view (looking along +y, z up)
// and the top view (looking down -z) side by side, orthographic, flat-shaded
// (Lambert, light from the viewer's upper left), drawn back to front. For the
// PNG that `drape simulate --out` and `drape garment --out` write; no GPU, no Qt.
#include "engine/cloth/mesh.hpp"

#include <opencv2/core.hpp>

#include <string>
#include <vector>

namespace drape::capture {

struct PictureMesh {
    const cloth::Positions* X = nullptr; ///< [m]
    const cloth::Triangles* F = nullptr;
    cv::Scalar colour{60, 60, 170};      ///< BGR
};

/// Both views, each `panel` px square, framed on the union of the meshes'
/// bounding boxes, with a title line and a 10 cm scale bar.
cv::Mat mesh_picture(const std::vector<PictureMesh>& meshes, const std::string& title, int panel = 520);

/// mesh_picture written as PNG. Throws FileError naming the path.
void write_mesh_picture(const std::string& path, const std::vector<PictureMesh>& meshes, const std::string& title,
                        int panel = 520);

} // namespace drape::capture
