#include "importers/garment.hpp"

namespace drape::importers {

cloth::ClothMesh garment_to_cloth(const ImportedMesh& garment, const Eigen::Vector3d& warp)
{
    return cloth::make_triangle_mesh(garment.X, garment.F, warp);
}

} // namespace drape::importers
