#pragma once
// Products derived from a measured record: the rectified texture image of the
// top view (the seed's fourth image) and the 3-D surface recovered from the
// stack of laser contours (the seed's figure 2b).
#include "engine/capture/measure.hpp"

#include <filesystem>

namespace drape::capture {

/// Top photo resampled to the vertical projection (orthographic view from
/// above): axis at the centre, +x right, +y up, `metres_per_pixel` [m/px]
/// (default 0.25 mm). Exact on the pedestal top; the hanging part is taken as a
/// cone from the disc edge to the hem height of each ray. Outside the traced
/// outline the image is white.
cv::Mat rectified_texture(const record::Record& rec, const Measurement& m, double metres_per_pixel = 0.25e-3);

/// Triangle mesh [m] through the Fourier series of every contour level plus the
/// pedestal edge ring at z = 0, `segments` vertices per ring. Needs >= 1 level.
struct SurfaceMesh {
    std::vector<Eigen::Vector3d> vertices;
    std::vector<std::array<int, 3>> triangles;
};
SurfaceMesh contour_surface(const record::Record& rec, const Measurement& m, int segments = 180);

/// Wavefront OBJ (metres). Throws FileError when the file cannot be written.
void write_obj(const SurfaceMesh& mesh, const std::filesystem::path& file);

} // namespace drape::capture
