#pragma once
// Cloth meshes: the seed's round sheet of square patches on a rectilinear grid
// (warp = u along world x, weft = v along world y), a rectangle, and a general
// triangle mesh. Positions are in metres, one row per vertex.
#include <Eigen/Core>

#include <array>
#include <vector>

namespace drape::cloth {

using Positions = Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor>; ///< n x 3 [m]
using Triangles = Eigen::Matrix<int, Eigen::Dynamic, 3, Eigen::RowMajor>;     ///< m x 3 vertex indices

/// Rectilinear grid structure of a grid mesh (absent for general meshes).
struct GridInfo {
    int nu = 0, nv = 0;      ///< grid nodes along u (warp) and v (weft)
    double hu = 0, hv = 0;   ///< node spacing [m]
    std::vector<int> index;  ///< (i + nu * j) -> vertex index, or -1 where the node is not part of the cloth
    int at(int i, int j) const
    {
        if (i < 0 || j < 0 || i >= nu || j >= nv) return -1;
        return index[static_cast<std::size_t>(i + nu * j)];
    }
    bool valid() const { return nu > 0 && nv > 0; }
};

struct ClothMesh {
    Positions X;                 ///< rest (flat, undeformed) positions [m]
    Triangles F;                 ///< triangles, counter-clockwise seen from +z at rest
    Eigen::MatrixX2d uv;         ///< material coordinates [m]: u along warp, v along weft
    GridInfo grid;               ///< present for grid meshes
    std::vector<char> on_grid_line; ///< per vertex: 1 if it sits exactly on its grid node (not snapped to the hem)
    std::vector<char> boundary;  ///< per vertex: 1 on the outer edge (hem)

    int vertex_count() const { return static_cast<int>(X.rows()); }
    /// Area lumped to vertices: a third of each incident triangle [m^2].
    Eigen::VectorXd vertex_areas() const;
    /// Total area of the triangles [m^2].
    double area() const;
};

/// Round sheet of square patches: an n x n grid of nodes spanning the diameter,
/// keeping the nodes inside the circle; the hem nodes are moved radially onto
/// the circle so the sheet's outline is the cut circle (the seed's sheet shape
/// without a staircase hem). Centre at (0, 0, z) [m]. Throws ParameterError when
/// diameter <= 0 or n < 5.
ClothMesh make_disc(double diameter, int n, double z = 0.0);

/// Where make_ring_disc refines: between inner_radius and outer_radius [m] from
/// the centre the spacing is factor times the nominal one, tapering linearly back
/// to it over `taper` [m] on either side. factor 1: uniform rings.
struct RingGrading {
    double inner_radius = 0, outer_radius = 0; ///< [m]
    double factor = 1;                         ///< (0, 1]
    double taper = 0;                          ///< [m]
};

/// Round sheet of triangles on concentric rings (no lattice directions): a
/// vertex at the centre, rings at the local spacing (nominally diameter / (n - 1),
/// as make_disc's), each with as many near-equilateral triangles as that spacing
/// asks and turned by the golden angle against the one inside it; the last ring
/// on the cut circle. Material coordinates as make_disc's (u = x + R, v = y + R);
/// no GridInfo (the general triangle model). Throws ParameterError when
/// diameter <= 0, n outside [5, 2000], the grading is out of range (factor in
/// [0.05, 1], taper >= 0, 0 <= inner radius <= outer radius) or the rings would
/// fold over each other (a grid too coarse for the grading).
ClothMesh make_ring_disc(double diameter, int n, const RingGrading& grading = {}, double z = 0.0);

/// Rectangle w x h [m] with nu x nv nodes, corner at `origin`, in the plane z = origin.z.
ClothMesh make_rectangle(double w, double h, int nu, int nv, const Eigen::Vector3d& origin = Eigen::Vector3d::Zero());

/// General triangle mesh (e.g. a garment panel). Material coordinates are the
/// rest positions projected on the best-fit plane, u along `warp` projected into it.
/// Throws ParameterError on an empty mesh, bad indices or non-finite coordinates.
ClothMesh make_triangle_mesh(const Positions& X, const Triangles& F, const Eigen::Vector3d& warp = Eigen::Vector3d::UnitX());

} // namespace drape::cloth
