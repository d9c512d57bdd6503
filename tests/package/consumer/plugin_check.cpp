// Loads the installed Qt Designer plugin as Designer does (QPluginLoader) and
// checks that the library it pulls in is the installed one.
//   plugin_check PLUGIN.so INSTALL_ROOT
#include <QApplication>
#include <QFile>
#include <QMetaProperty>
#include <QPluginLoader>
#include <QWidget>
#include <QtUiPlugin/QDesignerCustomWidgetInterface>

#include <cstdio>

int main(int argc, char** argv)
{
    QApplication app(argc, argv);
    if (argc != 3) return 2;
    QPluginLoader loader(QString::fromUtf8(argv[1]));
    if (!loader.load()) {
        std::fprintf(stderr, "cannot load %s: %s\n", argv[1], qPrintable(loader.errorString()));
        return 1;
    }
    auto* iface = qobject_cast<QDesignerCustomWidgetInterface*>(loader.instance());
    if (!iface || iface->name() != QLatin1String("drape::widget::DrapeView")) {
        std::fprintf(stderr, "not the DrapeView plugin\n");
        return 1;
    }
    QWidget* w = iface->createWidget(nullptr);
    if (!w || QString::fromLatin1(w->metaObject()->className()) != QLatin1String("drape::widget::DrapeView")) return 1;
    const QMetaProperty integ = w->metaObject()->property(w->metaObject()->indexOfProperty("integrator"));
    if (!integ.isEnumType()) {
        std::fprintf(stderr, "integrator is not an enum property\n");
        return 1;
    }
    // Which libdrape_widget came with it: the installed one.
    QFile maps(QStringLiteral("/proc/self/maps"));
    maps.open(QIODevice::ReadOnly);
    QString lib;
    for (const QByteArray& line : maps.readAll().split('\n'))
        if (line.contains("libdrape_widget.so")) lib = QString::fromUtf8(line.mid(line.indexOf('/')));
    std::printf("%s loaded %s (group %s)\n", argv[1], qPrintable(lib), qPrintable(iface->group()));
    delete w;
    return lib.startsWith(QString::fromUtf8(argv[2])) ? 0 : 1;
}
