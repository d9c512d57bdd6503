// Renders a DrapeView to a PNG (docs screenshots): builds a cloth, simulates it
// to rest (or for --time seconds of simulated time) and grabs the framebuffer.
//
//   drape_view_shot --out shot.png [--view iso|top|side] [--grid 40] [--integrator implicit]
//                   [--preset FILE] [--texture IMG] [--time T] [--size 800x600] [--outline]
//                   [--shape disc|square] [--pin X,Y]
#include "widget/drape_view.hpp"

#include <QApplication>
#include <QCommandLineParser>
#include <QElapsedTimer>
#include <QPolygonF>

#include <cmath>
#include <cstdio>

using drape::widget::DrapeView;

int main(int argc, char** argv)
{
    QApplication app(argc, argv);
    QCommandLineParser cl;
    cl.addHelpOption();
    cl.addOption({"out", "PNG to write", "file", "drape.png"});
    cl.addOption({"view", "top, side or iso", "view", "iso"});
    cl.addOption({"grid", "nodes across", "n", "40"});
    cl.addOption({"integrator", "integrator", "name", "implicit"});
    cl.addOption({"preset", "fabric preset", "preset", ""});
    cl.addOption({"texture", "texture image", "file", ""});
    cl.addOption({"time", "stop after this simulated time [s] (0 = at rest)", "t", "0"});
    cl.addOption({"timeout", "give up after this wall time [s]", "s", "240"});
    cl.addOption({"size", "WxH", "size", "800x600"});
    cl.addOption({"outline", "show the simulated shadow outline and a circle of the flat specimen as 'measured'"});
    cl.addOption({"pin", "pin the vertex nearest to this world point x,y [m] before running", "x,y", ""});
    cl.addOption({"shape", "cloth shape: disc or square", "shape", "disc"});
    cl.process(app);
    const QStringList wh = cl.value("size").split('x');

    DrapeView view;
    view.resize(wh.value(0).toInt(), wh.value(1).toInt());
    int errors = 0;
    QObject::connect(&view, &DrapeView::errorOccurred, [&](const QString& m) {
        ++errors;
        std::fprintf(stderr, "error: %s\n", qPrintable(m));
    });
    view.setGridSize(cl.value("grid").toInt());
    const auto integ = drape::widget::parseIntegrator(cl.value("integrator"));
    const auto viewPreset = drape::widget::parseViewPreset(cl.value("view"));
    const auto shape = drape::widget::parseClothShape(cl.value("shape"));
    if (!integ || !viewPreset || !shape) {
        std::fprintf(stderr, "error: unknown --integrator, --view or --shape\n");
        return 2;
    }
    view.setIntegrator(*integ);
    view.setFabricPreset(cl.value("preset"));
    view.setTexture(cl.value("texture"));
    view.setViewPreset(*viewPreset);
    view.setClothShape(*shape);
    view.show();
    bool rest = false;
    QObject::connect(&view, &DrapeView::restReached, [&] { rest = true; });
    QElapsedTimer clock;
    clock.start();
    while (view.controller()->vertexCount() == 0 && clock.elapsed() < 30000) app.processEvents(QEventLoop::AllEvents, 20);
    if (cl.isSet("outline")) {
        QPolygonF circle;
        const double r = view.sampleDiameter() * 0.5e-3;
        for (int k = 0; k < 360; ++k) circle << QPointF(r * std::cos(k * M_PI / 180), r * std::sin(k * M_PI / 180));
        view.showMeasuredOutline(circle);
    }
    if (cl.isSet("pin")) {
        while (!view.controller()->currentFrame() && clock.elapsed() < 30000) app.processEvents(QEventLoop::AllEvents, 20);
        const QStringList xy = cl.value("pin").split(',');
        const Eigen::Vector2d p(xy.value(0).toDouble(), xy.value(1).toDouble());
        const auto frame = view.controller()->currentFrame();
        int nearest = -1;
        double best = 1e300;
        for (int i = 0; frame && i < frame->x.rows(); ++i)
            if (const double d = (frame->x.row(i).head<2>().transpose() - p).norm(); d < best) {
                best = d;
                nearest = i;
            }
        if (nearest >= 0) view.controller()->setPinned(nearest, true);
    }
    const double until = cl.value("time").toDouble();
    view.setRunning(true);
    while (!rest && clock.elapsed() < cl.value("timeout").toDouble() * 1000 &&
           !(until > 0 && view.controller()->simulatedTime() >= until))
        app.processEvents(QEventLoop::AllEvents, 20);
    view.setRunning(false);
    for (int i = 0; i < 20; ++i) app.processEvents(QEventLoop::AllEvents, 20);
    const QImage img = view.grabFrame();
    if (!img.save(cl.value("out"))) {
        std::fprintf(stderr, "cannot write %s\n", qPrintable(cl.value("out")));
        return 1;
    }
    std::printf("%s: %dx%d, %s, t = %.3f s, %s, %.1f s wall\n", qPrintable(cl.value("out")), img.width(), img.height(),
                qPrintable(view.controller()->statusText()), view.controller()->simulatedTime(),
                rest ? "at rest" : "not at rest", clock.elapsed() / 1000.0);
    return errors ? 1 : 0;
}
