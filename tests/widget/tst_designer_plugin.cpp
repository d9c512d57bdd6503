// The Designer plugin loads like Designer loads it (QPluginLoader), describes
// DrapeView with valid defaults, and a .ui form using DrapeView builds through
// QUiLoader into a working view.
#include "widget/drape_view.hpp"

#include <QFileInfo>
#include <QPluginLoader>
#include <QSignalSpy>
#include <QUiLoader>
#include <QXmlStreamReader>
#include <QTest>
#include <QtUiPlugin/QDesignerCustomWidgetInterface>

using drape::widget::DrapeController;
using drape::widget::DrapeView;

class TstDesignerPlugin : public QObject {
    Q_OBJECT

private slots:
    void pluginLoadsAndDescribesTheWidget()
    {
        QPluginLoader loader(QStringLiteral(DRAPE_DESIGNER_PLUGIN_FILE));
        QVERIFY2(loader.load(), qPrintable(loader.errorString()));
        QCOMPARE(loader.metaData().value("IID").toString(),
                 QStringLiteral("org.qt-project.Qt.QDesignerCustomWidgetInterface"));
        auto* iface = qobject_cast<QDesignerCustomWidgetInterface*>(loader.instance());
        QVERIFY(iface);
        QCOMPARE(iface->name(), QStringLiteral("drape::widget::DrapeView"));
        QCOMPARE(iface->group(), QStringLiteral("Drapekit"));
        QVERIFY(!iface->icon().isNull());
        QVERIFY(!iface->icon().pixmap(32, 32).isNull());
        QVERIFY(!iface->isContainer());
        QVERIFY(iface->includeFile().endsWith("drape_view.hpp"));
        QVERIFY(QFileInfo::exists(QStringLiteral(DRAPE_SOURCE_DIR "/") + iface->includeFile()));

        // domXml: well-formed, names the class, and every default property exists on DrapeView.
        const QString xml = iface->domXml();
        QXmlStreamReader r(xml);
        QString widgetClass;
        QStringList props;
        while (!r.atEnd()) {
            r.readNext();
            if (r.isStartElement() && r.name() == QLatin1String("widget") && widgetClass.isEmpty())
                widgetClass = r.attributes().value("class").toString();
            if (r.isStartElement() && r.name() == QLatin1String("property"))
                props << r.attributes().value("name").toString();
        }
        QVERIFY2(!r.hasError(), qPrintable(r.errorString()));
        QCOMPARE(widgetClass, iface->name());
        QVERIFY(props.contains("gridSize"));
        QVERIFY(props.contains("running"));

        QWidget parent;
        QWidget* w = iface->createWidget(&parent);
        auto* view = qobject_cast<DrapeView*>(w);
        QVERIFY(view);
        for (const QString& p : props) {
            if (p == QLatin1String("geometry")) continue;
            QVERIFY2(view->metaObject()->indexOfProperty(qPrintable(p)) >= 0, qPrintable(p));
            const int idx = view->metaObject()->indexOfProperty(qPrintable(p));
            QVERIFY2(view->metaObject()->property(idx).isDesignable(), qPrintable(p));
        }
    }

    void uiFileBuildsThroughQUiLoader()
    {
        QUiLoader loader;
        loader.clearPluginPaths();
        loader.addPluginPath(QFileInfo(QStringLiteral(DRAPE_DESIGNER_PLUGIN_FILE)).absolutePath());
        QVERIFY2(loader.availableWidgets().contains("drape::widget::DrapeView"),
                 qPrintable(loader.availableWidgets().join(", ")));
        QFile f(QStringLiteral(DRAPE_WIDGET_TEST_DATA "/drape_form.ui"));
        QVERIFY(f.open(QIODevice::ReadOnly));
        std::unique_ptr<QWidget> form(loader.load(&f));
        QVERIFY2(form, qPrintable(loader.errorString()));
        auto* view = form->findChild<DrapeView*>("drapeView");
        QVERIFY(view);
        // The .ui's property values reached the widget.
        QCOMPARE(view->sampleDiameter(), 240.0);
        QCOMPARE(view->discDiameter(), 180.0);
        QCOMPARE(view->gridSize(), 14);
        QCOMPARE(view->viewPreset(), drape::widget::Drape::Top);
        QVERIFY(view->running());
        QSignalSpy errors(view, &DrapeView::errorOccurred);
        QSignalSpy progress(view, &DrapeView::progress);
        form->show();
        QVERIFY(QTest::qWaitForWindowExposed(form.get()));
        // And it simulates: a cloth with the .ui's geometry appears and moves.
        QTRY_VERIFY_WITH_TIMEOUT(view->controller()->vertexCount() > 0, 30000);
        QVERIFY(progress.wait(30000));
        QTRY_VERIFY_WITH_TIMEOUT(view->controller()->simulatedTime() > 0.01, 30000);
        QCOMPARE(view->controller()->currentMesh()->sampleRadius, 0.12);
        QCOMPARE(view->controller()->currentMesh()->discRadius, 0.09);
        QCOMPARE(errors.count(), 0);
        const QImage img = view->grabFrame();
        QVERIFY(!img.isNull());
        img.save(QDir::temp().filePath("tst_designer_plugin_form.png"));
    }
};

QTEST_MAIN(TstDesignerPlugin)
#include "tst_designer_plugin.moc"
