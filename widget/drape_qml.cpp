#include "widget/drape_qml.hpp"

#include "widget/cloth_geometry.hpp"
#include "widget/drape_controller.hpp"
#include "widget/floor_boards.hpp"
#include "widget/line_geometry.hpp"

#include <QQmlEngine>
#include <QUrl>

#include <mutex>

namespace drape::widget {

void registerDrapeQmlTypes()
{
    static std::once_flag once;
    std::call_once(once, [] {
        const char* uri = "Drapekit";
        qmlRegisterType<DrapeController>(uri, 1, 0, "DrapeController");
        qmlRegisterUncreatableType<ClothGeometry>(uri, 1, 0, "ClothGeometry",
                                                  QStringLiteral("use DrapeController.clothGeometry"));
        qmlRegisterUncreatableType<LineGeometry>(uri, 1, 0, "LineGeometry",
                                                 QStringLiteral("use DrapeController's outlines"));
        qmlRegisterUncreatableType<FloorBoardsGeometry>(uri, 1, 0, "FloorBoardsGeometry",
                                                        QStringLiteral("use DrapeController.floorBoards"));
        qmlRegisterType(QUrl(QStringLiteral("qrc:/drapekit/qml/DrapeScene.qml")), uri, 1, 0, "DrapeScene");
    });
}

} // namespace drape::widget
