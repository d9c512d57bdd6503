// drape-demo: the fitting demo app. With a display it opens the window; with
// --script it runs one fitting without a user (e.g. under Xvfb), writes the
// screenshot and a JSON summary, and exits (0 ok, 1 failed, 2 usage).
#include "demo/main_window.hpp"
#include "engine/cloth/blas_threads.hpp"

#include <QApplication>
#include <QCommandLineParser>

#include <cstdio>

int main(int argc, char** argv)
{
    drape::cloth::portable_blas_kernel(); // before Qt's threads (it sets the environment)
    QApplication app(argc, argv);
    QApplication::setApplicationName(QStringLiteral("drape-demo"));
    QApplication::setApplicationVersion(QStringLiteral("0.1"));

    QCommandLineParser cli;
    cli.setApplicationDescription(QStringLiteral("Drapekit fitting demo: drape a garment on a mannequin or a table with a fabric preset."));
    cli.addHelpOption();
    cli.addVersionOption();
    const QCommandLineOption script({"s", "script"}, "Run a scripted fitting and exit: fitting (skirt on the mannequin) or tablecloth.", "name");
    const QCommandLineOption garment("garment", "Garment: skirt | tablecloth | garment (overrides the script's).", "name");
    const QCommandLineOption garmentFile("garment-file", "Garment mesh to drape (OBJ, Collada, glTF, ...; its top boundary is pinned): implies --garment garment.", "file");
    const QCommandLineOption fabric("fabric", "Fabric name (or part of it) from the library / starter presets.", "name");
    const QCommandLineOption fabric2("compare", "Second fabric, draped side by side.", "name");
    const QCommandLineOption shot("screenshot", "Write a PNG of the view(s) after the drape (script mode).", "file");
    const QCommandLineOption json("json", "Write the JSON summary here too (script mode; it always goes to stdout).", "file");
    const QCommandLineOption mannequin("mannequin", "Mannequin mesh (default: the MakeHuman body of assimp-testmodels).", "file");
    const QCommandLineOption unit("unit", "Mannequin unit: file | mm | cm | m.", "unit", "file");
    const QCommandLineOption up("up", "Mannequin up axis: file | y | z.", "axis", "file");
    const QCommandLineOption library("library", "Fabric library (SQLite); default $DRAPE_LIBRARY or ~/.local/share/drapekit/library.sqlite.", "file");
    const QCommandLineOption size("size", "Window size WxH (e.g. 1100x760).", "size");
    const QCommandLineOption list("list-fabrics", "Print the fabrics the demo offers and exit.");
    const QCommandLineOption fit("fit", "Fit a fabric to a record folder (or a folder of records of one fabric) as the Fit button does, "
                                        "show its predictions of the standard set-ups, write --screenshot of the window and exit.", "dir");
    cli.addOptions({script, garment, garmentFile, fabric, fabric2, shot, json, mannequin, unit, up, library, size, list, fit});
    cli.process(app);

    drape::demo::DemoOptions o;
    o.mannequin = cli.value(mannequin);
    o.unit = cli.value(unit);
    o.up = cli.value(up);
    o.library = cli.value(library);

    drape::demo::ScriptOptions s;
    if (cli.isSet(script)) {
        const QString name = cli.value(script);
        if (name == "fitting" || name == "skirt") s.garment = "skirt";
        else if (name == "tablecloth") s.garment = "tablecloth";
        else {
            std::fprintf(stderr, "drape-demo: unknown script \"%s\" (expected fitting or tablecloth)\n", qPrintable(name));
            return 2;
        }
    }
    if (cli.isSet(garmentFile)) {
        s.garment = "garment";
        s.garmentFile = cli.value(garmentFile);
    }
    if (cli.isSet(garment)) s.garment = cli.value(garment);
    s.fabric = cli.value(fabric);
    s.fabric2 = cli.value(fabric2);
    s.screenshot = cli.value(shot);
    s.json = cli.value(json);

    drape::demo::MainWindow w(o);
    if (cli.isSet(list)) {
        for (const auto& f : w.fabrics()) std::printf("%s\t%s\n", f.name.c_str(), f.origin.c_str());
        return 0;
    }
    if (cli.isSet(size)) {
        const QStringList wh = cli.value(size).split('x');
        if (wh.size() != 2 || wh[0].toInt() < 200 || wh[1].toInt() < 200) {
            std::fprintf(stderr, "drape-demo: --size must be WxH with both >= 200 (got \"%s\")\n", qPrintable(cli.value(size)));
            return 2;
        }
        w.resize(wh[0].toInt(), wh[1].toInt());
    }
    w.show();
    if (cli.isSet(fit)) {
        int code = 0;
        QObject::connect(&w, &drape::demo::MainWindow::fitFinished, &app, [&](bool ok, const QString& msg) {
            std::printf("%s: %s\n", ok ? "fitted" : "fit failed", qPrintable(msg));
            if (ok && !s.screenshot.isEmpty() && !w.grab().save(s.screenshot)) {
                std::fprintf(stderr, "drape-demo: cannot write %s\n", qPrintable(s.screenshot));
                ok = false;
            }
            code = ok ? 0 : 1;
            QApplication::exit(code);
        });
        QString err;
        if (!w.fitRecords(cli.value(fit), &err)) {
            std::fprintf(stderr, "drape-demo: %s\n", qPrintable(err));
            return 1;
        }
        app.exec();
        return code;
    }
    if (!cli.isSet(script) && !cli.isSet(garment) && !cli.isSet(garmentFile)) return app.exec();

    int code = 0;
    QObject::connect(&w, &drape::demo::MainWindow::scriptFinished, &app, [&code](int c) {
        code = c;
        QApplication::exit(c);
    });
    w.runScript(s);
    app.exec();
    return code;
}
