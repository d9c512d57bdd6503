#include "widget/floor_boards.hpp"

#include "widget/drape_frame.hpp"

#include <vector>

namespace drape::widget {

FloorBoardsGeometry::FloorBoardsGeometry(QQuick3DObject* parent) : QQuick3DGeometry(parent)
{
    setPrimitiveType(PrimitiveType::Triangles);
    setStride(6 * int(sizeof(float)));
    addAttribute(Attribute::PositionSemantic, 0, Attribute::F32Type);
    addAttribute(Attribute::NormalSemantic, 3 * sizeof(float), Attribute::F32Type);
}

void FloorBoardsGeometry::setFloorHeight(double z)
{
    if (z == m_z) return;
    m_z = z;
    struct Board { double x0, y0; int nx, ny; }; // [mm], squares along x and y
    const Board boards[] = {{230, -150, 7, 12}, {-405, -150, 7, 12}, {-150, 230, 12, 4}, {-150, -330, 12, 4}};
    const double lift = 0.5e-3; // [m] above the floor: no depth fighting with the floor plane
    std::vector<float> v;
    m_squares = 0;
    for (const Board& b : boards)
        for (int i = 0; i < b.nx; ++i)
            for (int j = 0; j < b.ny; ++j) {
                if ((i + j) % 2 != 0) continue;
                const double x0 = (b.x0 + 25.0 * i) * 1e-3, y0 = (b.y0 + 25.0 * j) * 1e-3, s = 25e-3;
                // Two triangles, counter-clockwise seen from above (+z).
                const double corners[6][2] = {{x0, y0}, {x0 + s, y0}, {x0 + s, y0 + s}, {x0, y0}, {x0 + s, y0 + s}, {x0, y0 + s}};
                for (const auto& c : corners) {
                    const QVector3D p = toScene(c[0], c[1], z + lift);
                    v.insert(v.end(), {p.x(), p.y(), p.z(), 0.0f, 1.0f, 0.0f});
                }
                ++m_squares;
            }
    setVertexData(QByteArray(reinterpret_cast<const char*>(v.data()), qsizetype(v.size() * sizeof(float))));
    setBounds(toScene(-0.5, 0.5, z), toScene(0.5, -0.5, z + 2 * lift));
    update();
}

} // namespace drape::widget
