// Measures the live view: time from "load preset" to the first rendered frame of
// the cloth, then rendered frames per second, cloth frames per second and the
// event loop's worst stall while a cloth simulates. Prints numbers; asserts nothing.
//
//   drape_view_fps [--grid 113] [--seconds 10] [--integrator implicit] [--preset FILE|seed-table1|NAME]
//                  [--size 800x600] [--rest] [--library-ops N]
//
// --rest: instead of running the integrator live, drape to rest with the static
// solver (DrapeView::drapeToRest) and measure the worst stall during that.
// --library-ops N: afterwards, set the fabric by a library name N times (a
// temporary library with the starter fabrics) and print the slowest.
#include "widget/drape_view.hpp"

#include "engine/library/resolve.hpp"

#include <QApplication>
#include <QCommandLineParser>
#include <QElapsedTimer>
#include <QQuickWidget>
#include <QQuickWindow>
#include <QTemporaryDir>
#include <QTimer>

#include <cstdio>

using drape::widget::DrapeView;

int main(int argc, char** argv)
{
    QApplication app(argc, argv);
    QCommandLineParser cl;
    cl.addHelpOption();
    cl.addOption({"grid", "nodes across the specimen (113 gives ~10,000 particles)", "n", "113"});
    cl.addOption({"seconds", "measuring time [s]", "s", "10"});
    cl.addOption({"integrator", "integrator name", "name", "implicit"});
    cl.addOption({"preset", "fabric preset file or built-in name (default: the table defaults written to a file)", "preset", ""});
    cl.addOption({"size", "view size WxH", "size", "800x600"});
    cl.addOption({"rest", "drape to rest with the static solver instead of the live integrator"});
    cl.addOption({"library-ops", "set the fabric by a library name this many times and time it", "n", "0"});
    cl.process(app);
    const QStringList wh = cl.value("size").split('x');
    const int width = wh.value(0).toInt() > 0 ? wh.value(0).toInt() : 800;
    const int height = wh.value(1).toInt() > 0 ? wh.value(1).toInt() : 600;

    DrapeView view;
    view.resize(width, height);
    QObject::connect(&view, &DrapeView::errorOccurred,
                     [](const QString& m) { std::fprintf(stderr, "error: %s\n", qPrintable(m)); });
    view.show();
    // Let the scene come up with the default cloth first, so the measurement is
    // "load preset -> first frame", not QML start-up.
    QElapsedTimer warm;
    warm.start();
    while (warm.elapsed() < 1500) app.processEvents(QEventLoop::AllEvents, 50);

    QQuickWindow* win = view.quickWidget()->quickWindow();
    long rendered = 0;
    QObject::connect(win, &QQuickWindow::afterRendering, [&] { ++rendered; }); // GUI thread for QQuickWidget
    long applied = 0;
    QObject::connect(view.controller(), &drape::widget::DrapeController::frameApplied, [&] { ++applied; });

    // ---- load preset -> first frame --------------------------------------------
    const auto integ = drape::widget::parseIntegrator(cl.value("integrator"));
    if (!integ) {
        std::fprintf(stderr, "error: unknown --integrator %s\n", qPrintable(cl.value("integrator")));
        return 2;
    }
    view.setIntegrator(*integ);
    QTemporaryDir tmp;
    QString preset = cl.value("preset");
    if (preset.isEmpty()) { // a real file, so the measurement includes reading and parsing it
        preset = tmp.filePath("fabric.json");
        view.saveFabricPreset(preset);
    }
    QElapsedTimer t;
    t.start();
    view.setGridSize(cl.value("grid").toInt());
    view.setFabricPreset(preset);
    view.controller()->createCloth();
    qint64 meshAt = -1, firstFrameAt = -1, firstRenderAt = -1;
    QObject::connect(view.controller(), &drape::widget::DrapeController::meshChanged, [&] {
        if (meshAt < 0) meshAt = t.elapsed();
    });
    QObject::connect(view.controller(), &drape::widget::DrapeController::frameApplied, [&] {
        if (meshAt >= 0 && firstFrameAt < 0) firstFrameAt = t.elapsed();
    });
    QObject::connect(win, &QQuickWindow::afterRendering, [&] {
        if (firstFrameAt >= 0 && firstRenderAt < 0) firstRenderAt = t.elapsed();
    });
    while (firstRenderAt < 0 && t.elapsed() < 120000) app.processEvents(QEventLoop::AllEvents, 5);
    const int n = view.controller()->vertexCount();
    std::printf("particles: %d (grid %d, integrator %s)\n", n, view.gridSize(), qPrintable(drape::widget::toString(view.integrator())));
    std::printf("load preset -> mesh built: %lld ms, -> first cloth frame applied: %lld ms, -> first frame rendered: %lld ms\n",
                static_cast<long long>(meshAt), static_cast<long long>(firstFrameAt), static_cast<long long>(firstRenderAt));

    // ---- live simulation --------------------------------------------------------
    const double seconds = cl.value("seconds").toDouble();
    QElapsedTimer gapClock;
    qint64 worstGap = 0;
    QTimer tick; // a 10 ms heartbeat: its worst late arrival is the UI's worst stall
    tick.setInterval(10);
    QObject::connect(&tick, &QTimer::timeout, [&] {
        worstGap = std::max(worstGap, gapClock.restart());
    });
    const double simStart = view.controller()->simulatedTime();
    rendered = 0;
    applied = 0;
    const bool toRest = cl.isSet("rest");
    bool rest = false;
    QObject::connect(&view, &DrapeView::restReached, [&] { rest = true; });
    double lastFraction = -1;
    QObject::connect(&view, &DrapeView::drapeProgress, [&](double f, const QString&) { lastFraction = f; });
    if (toRest) view.drapeToRest();
    else view.setRunning(true);
    QElapsedTimer run;
    run.start();
    gapClock.start();
    tick.start();
    while (run.elapsed() < seconds * 1000 && !rest) {
        // Keep the view busy like a user would: orbit a little every frame, so it renders continuously.
        view.controller()->orbit(0.5, 0.0);
        app.processEvents(QEventLoop::AllEvents, 5);
    }
    const double wall = run.elapsed() / 1000.0;
    tick.stop();
    view.setRunning(false);
    const auto f = view.controller()->currentFrame();
    std::printf("live view for %.2f s%s: %.1f rendered frames/s, %.1f cloth frames/s, simulated %.3f s (%.3f x real time), %ld steps, worst UI stall %lld ms\n",
                wall, rest ? " (cloth reached rest)" : "", rendered / wall, applied / wall,
                view.controller()->simulatedTime() - simStart, (view.controller()->simulatedTime() - simStart) / wall,
                f ? f->steps : 0L, static_cast<long long>(worstGap));
    if (toRest)
        std::printf("drape to rest: %s, last progress fraction %.2f\n", rest ? "reached rest" : "stopped by --seconds", lastFraction);

    // ---- library operations on the GUI thread ------------------------------------
    if (const int ops = cl.value("library-ops").toInt(); ops > 0) {
        QTemporaryDir libDir;
        const QString path = libDir.filePath("library.sqlite");
        auto lib = drape::library::open_library(path.toStdString(), drape::library::FabricLibrary::Mode::ReadWrite);
        drape::library::add_starter_fabrics(lib);
        view.setLibraryPath(path);
        const QStringList names = {"Silk (class preset)", "Denim (class preset)", "Wool worsted (class preset)",
                                   "Cotton plain weave (class preset)"};
        qint64 worstOp = 0;
        for (int i = 0; i < ops; ++i) {
            QElapsedTimer op;
            op.start();
            view.setFabricPreset(names[i % names.size()]);
            worstOp = std::max(worstOp, op.elapsed());
            app.processEvents(QEventLoop::AllEvents, 5);
        }
        std::printf("library: %d fabric lookups by name on the GUI thread, slowest %lld ms\n", ops,
                    static_cast<long long>(worstOp));
    }
    return 0;
}
