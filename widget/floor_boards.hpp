#pragma once
// The drape lab's four calibration chessboards on the floor sheet
// (shared/data/drape-lab/README.md: 25 mm squares, square (i, j) black when
// i + j is even), as geometry of the black squares, so the top and iso views
// can be laid next to the record's photos.
#include "widget/drape_widget_export.hpp"
#include <QQuick3DGeometry>

namespace drape::widget {

class DRAPE_WIDGET_EXPORT FloorBoardsGeometry : public QQuick3DGeometry {
    Q_OBJECT
public:
    explicit FloorBoardsGeometry(QQuick3DObject* parent = nullptr);
    /// Rebuilds the squares at world height z [m] (a hair above the floor plane).
    void setFloorHeight(double z);
    int squareCount() const { return m_squares; }

private:
    double m_z = 1e300;
    int m_squares = 0;
};

} // namespace drape::widget
