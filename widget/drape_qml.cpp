#include "widget/drape_qml.hpp"

#include "widget/drape_controller.hpp"
#include "widget/line_geometry.hpp"
#include "widget/mesh_geometry.hpp"
#include "widget/scene.hpp"

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
        qmlRegisterUncreatableType<Scene>(uri, 1, 0, "Scene", QStringLiteral("a host fills a Scene from C++"));
        qmlRegisterUncreatableType<SceneItem>(uri, 1, 0, "SceneItem", QStringLiteral("use Scene.items"));
        qmlRegisterType<SceneTextureData>(uri, 1, 0, "SceneTexture");
        qmlRegisterUncreatableType<MeshGeometry>(uri, 1, 0, "MeshGeometry", QStringLiteral("use Scene.items"));
        qmlRegisterUncreatableType<LineGeometry>(uri, 1, 0, "LineGeometry", QStringLiteral("use Scene.items"));
        qmlRegisterType(QUrl(QStringLiteral("qrc:/drapekit/qml/SceneView.qml")), uri, 1, 0, "SceneView");
        qmlRegisterType(QUrl(QStringLiteral("qrc:/drapekit/qml/DrapeScene.qml")), uri, 1, 0, "DrapeScene");
    });
}

} // namespace drape::widget
