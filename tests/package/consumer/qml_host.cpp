// A QML-only host: links Qt Quick, not Drapekit, and loads a QML file that
// imports Drapekit (found through QML_IMPORT_PATH).
//   qml_host HOST.qml INSTALL_ROOT
#include <QFile>
#include <QGuiApplication>
#include <QQmlEngine>
#include <QQuickItem>
#include <QQuickView>
#include <QTimer>

#include <cmath>
#include <cstdio>

int main(int argc, char** argv)
{
    QGuiApplication app(argc, argv);
    if (argc != 3) return 2;
    QQuickView view;
    view.resize(480, 360);
    view.setSource(QUrl::fromLocalFile(QString::fromUtf8(argv[1])));
    if (view.status() != QQuickView::Ready) {
        for (const QQmlError& e : view.errors()) std::fprintf(stderr, "%s\n", qPrintable(e.toString()));
        return 1;
    }
    view.show();
    QObject* controller = view.rootObject()->property("controller").value<QObject*>();
    if (!controller) return 1;
    int code = 1;
    QTimer poll;
    QObject::connect(&poll, &QTimer::timeout, [&] {
        if (!controller->property("hasResults").toBool()) return;
        const double d = controller->property("drapeCoefficient").toDouble();
        QString lib;
        QFile maps(QStringLiteral("/proc/self/maps"));
        maps.open(QIODevice::ReadOnly);
        for (const QByteArray& line : maps.readAll().split('\n'))
            if (line.contains("libdrape_widget.so")) lib = QString::fromUtf8(line.mid(line.indexOf('/')));
        std::printf("QML host: D = %.1f %% with %s\n", d, qPrintable(lib));
        code = std::isfinite(d) && lib.startsWith(QString::fromUtf8(argv[2])) ? 0 : 1;
        app.quit();
    });
    poll.start(100);
    QTimer::singleShot(240000, &app, [&] { std::fprintf(stderr, "timed out\n"); app.exit(1); });
    app.exec();
    return code;
}
