// A CAD embedding DrapeView (the example of docs/widget.md): a fabric from its
// library by name, drape to rest, read the drape coefficient back.
//   drape_consumer LIBRARY.sqlite SCREENSHOT.png
#include <drapekit/engine/library/resolve.hpp>
#include <drapekit/widget/drape_view.hpp>

#include <QApplication>
#include <QTimer>

#include <cmath>
#include <cstdio>

int main(int argc, char** argv)
{
    QApplication app(argc, argv);
    if (argc != 3) return 2;
    // The user's library (created with the starter fabrics on first use).
    auto lib = drape::library::open_library(argv[1], drape::library::FabricLibrary::Mode::ReadWrite);
    drape::library::add_starter_fabrics(lib);

    drape::widget::DrapeView view;
    view.resize(640, 480);
    view.setLibraryPath(QString::fromUtf8(argv[1]));
    view.setFabricPreset("Denim (class preset)"); // a library name
    view.setGridSize(21);
    view.setViewPreset(drape::widget::Drape::Iso);
    int code = 1;
    QObject::connect(&view, &drape::widget::DrapeView::errorOccurred, [&](const QString& m) {
        std::fprintf(stderr, "error: %s\n", qPrintable(m));
        app.exit(1);
    });
    QObject::connect(&view, &drape::widget::DrapeView::drapeProgress, [](double f, const QString& s) {
        std::printf("%3.0f %%  %s\n", 100 * f, qPrintable(s));
    });
    QObject::connect(&view, &drape::widget::DrapeView::resultsReady, [&] {
        const double d = view.drapeCoefficient();
        std::printf("%s: D = %.1f %%, %d vertices\n", view.controller()->preset().name.c_str(), d, int(view.positions().rows()));
        const bool saved = view.grabFrame().save(QString::fromUtf8(argv[2]));
        code = std::isfinite(d) && d > 50 && d < 100 && saved ? 0 : 1;
        app.quit();
    });
    view.show();
    view.drapeToRest();
    QTimer::singleShot(240000, &app, [&] { std::fprintf(stderr, "timed out\n"); app.exit(1); });
    app.exec();
    return code;
}
