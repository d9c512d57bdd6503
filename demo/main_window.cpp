#include "demo/main_window.hpp"

#include "engine/estimate/fit.hpp"
#include "engine/estimate/predict.hpp"
#include "engine/estimate/measured.hpp"
#include "engine/library/fabric_library.hpp"

#include <QApplication>
#include <QCheckBox>
#include <QComboBox>
#include <QDir>
#include <QFile>
#include <QFileDialog>
#include <QFileInfo>
#include <QFormLayout>
#include <QHBoxLayout>
#include <QJsonArray>
#include <QJsonDocument>
#include <QJsonObject>
#include <QLabel>
#include <QLineEdit>
#include <QMessageBox>
#include <QPainter>
#include <QProgressBar>
#include <QPushButton>
#include <QSignalBlocker>
#include <QSplitter>
#include <QStatusBar>
#include <QTimer>
#include <QHeaderView>
#include <QToolButton>
#include <QTreeWidget>
#include <QVBoxLayout>

#include <cctype>
#include <cmath>
#include <filesystem>

#ifndef DRAPE_SOURCE_DIR
#define DRAPE_SOURCE_DIR "."
#endif

namespace drape::demo {

namespace {

importers::ImportOptions importOptions(const DemoOptions& o)
{
    importers::ImportOptions io;
    io.unit = importers::parse_unit(o.unit.toStdString(), "--unit");
    io.up = importers::parse_up_axis(o.up.toStdString(), "--up");
    return io;
}

} // namespace

MainWindow::MainWindow(const DemoOptions& options, QWidget* parent) : QMainWindow(parent), m_options(options)
{
    if (m_options.starterDir.isEmpty()) m_options.starterDir = QStringLiteral(DRAPE_SOURCE_DIR "/data/library");
    setWindowTitle(tr("Drapekit fitting demo"));
    buildUi();
    reloadFabrics();
    QString err;
    const QString path = m_options.mannequin.isEmpty() ? QString::fromStdString(importers::default_mannequin_path()) : m_options.mannequin;
    if (!loadMannequin(path, &err)) showMessage(tr("Mannequin: %1").arg(err));
    // Open on the scene the controls name, not the view's default drapemeter disc.
    showChoices();
}

MainWindow::~MainWindow()
{
    m_fitJob.cancel();
}

void MainWindow::buildUi()
{
    auto* central = new QWidget(this);
    auto* h = new QHBoxLayout(central);

    auto* panel = new QWidget(central);
    // Wide enough for the library's longest names beside their numbers
    // ("Cotton plain weave (class preset)"); the view takes the rest.
    panel->setMaximumWidth(440);
    auto* form = new QFormLayout(panel);

    auto* mrow = new QHBoxLayout;
    m_mannequinPath = new QLineEdit(panel);
    m_mannequinPath->setReadOnly(true);
    auto* browse = new QToolButton(panel);
    browse->setText(QStringLiteral("…"));
    browse->setToolTip(tr("Import a mannequin (OBJ, Collada/ZAE, glTF, FBX, PLY, STL)"));
    connect(browse, &QToolButton::clicked, this, &MainWindow::chooseMannequin);
    mrow->addWidget(m_mannequinPath);
    mrow->addWidget(browse);
    form->addRow(tr("Mannequin"), mrow);

    m_garment = new QComboBox(panel);
    m_garment->setObjectName(QStringLiteral("garment"));
    m_garment->addItem(tr("Circular skirt on the mannequin"), QStringLiteral("skirt"));
    m_garment->addItem(tr("Round tablecloth on a round table"), QStringLiteral("tablecloth"));
    m_garment->addItem(tr("Imported garment mesh…"), QStringLiteral("garment"));
    form->addRow(tr("Garment"), m_garment);
    connect(m_garment, &QComboBox::activated, this, [this](int i) {
        if (m_garment->itemData(i).toString() == QLatin1String("garment") && m_garmentFile.isEmpty()) chooseGarmentFile();
    });

    addLibraryBrowser(panel, form);
    m_fabricA = new QComboBox(panel);
    m_fabricA->setObjectName(QStringLiteral("fabricA"));
    form->addRow(tr("Fabric"), m_fabricA);

    m_compare = new QCheckBox(tr("Compare with a second fabric"), panel);
    m_compare->setObjectName(QStringLiteral("compare"));
    form->addRow(m_compare);
    m_fabricB = new QComboBox(panel);
    m_fabricB->setObjectName(QStringLiteral("fabricB"));
    m_fabricB->setEnabled(false);
    form->addRow(tr("Second fabric"), m_fabricB);

    addActions(panel, form);
    m_split = new QSplitter(Qt::Horizontal, central);
    m_viewA = new FittingView(m_split);
    m_viewB = new FittingView(m_split);
    m_viewB->setClothColor(QColor(0x2f, 0x6f, 0xb0));
    m_viewB->hide();
    h->addWidget(panel);
    h->addWidget(m_split, 1);
    setCentralWidget(central);

    connectControls();
    resize(1180, 760);
}

void MainWindow::addLibraryBrowser(QWidget* panel, QFormLayout* form)
{
    // The library browser: search, weight, drape coefficient; a click picks the fabric.
    m_search = new QLineEdit(panel);
    m_search->setObjectName(QStringLiteral("fabricSearch"));
    m_search->setPlaceholderText(tr("Search the fabric library…"));
    m_search->setClearButtonEnabled(true);
    form->addRow(m_search);
    m_browser = new QTreeWidget(panel);
    m_browser->setObjectName(QStringLiteral("fabricBrowser"));
    m_browser->setColumnCount(4);
    m_browser->setHeaderLabels({tr("Fabric"), tr("g/m²"), tr("D %"), tr("from")});
    m_browser->setRootIsDecorated(false);
    m_browser->setSortingEnabled(true);
    m_browser->setMinimumHeight(150);
    // The name takes what the numbers leave: they are sized to their contents.
    m_browser->header()->setStretchLastSection(false);
    m_browser->header()->setSectionResizeMode(0, QHeaderView::Stretch);
    for (int c = 1; c < 4; ++c) m_browser->header()->setSectionResizeMode(c, QHeaderView::ResizeToContents);
    m_browser->setToolTip(tr("Click: the fabric to drape. Ctrl+click: the second fabric (compare)."));
    form->addRow(m_browser);
    connect(m_search, &QLineEdit::textChanged, this, &MainWindow::filterBrowser);
    connect(m_browser, &QTreeWidget::itemClicked, this, [this](QTreeWidgetItem* item) {
        const int i = item->data(0, Qt::UserRole).toInt();
        if (QApplication::keyboardModifiers() & Qt::ControlModifier) {
            m_compare->setChecked(true);
            m_fabricB->setCurrentIndex(i);
        } else {
            m_fabricA->setCurrentIndex(i);
        }
    });
}

void MainWindow::addActions(QWidget* panel, QFormLayout* form)
{
    m_fit = new QPushButton(tr("Fit a fabric from a record…"), panel);
    m_fit->setObjectName(QStringLiteral("fit"));
    m_fit->setToolTip(tr("Fits the fabric parameters to a drape-test record folder (meta.json + contours.csv) "
                         "or a folder of records of one fabric, then adds the result to the library."));
    connect(m_fit, &QPushButton::clicked, this, &MainWindow::fitFromRecord);
    form->addRow(m_fit);
    m_predictions = new QLabel(panel);
    m_predictions->setObjectName(QStringLiteral("predictions"));
    m_predictions->setWordWrap(true);
    m_predictions->setTextFormat(Qt::RichText);
    m_predictions->setVisible(false);
    form->addRow(m_predictions);

    auto* brow = new QHBoxLayout;
    m_drape = new QPushButton(tr("Drape"), panel);
    m_drape->setObjectName(QStringLiteral("drape"));
    m_drape->setDefault(true);
    m_cancel = new QPushButton(tr("Cancel"), panel);
    m_cancel->setEnabled(false);
    brow->addWidget(m_drape);
    brow->addWidget(m_cancel);
    form->addRow(brow);

    m_progress = new QProgressBar(panel);
    m_progress->setRange(0, 1000);
    m_progress->setValue(0);
    form->addRow(m_progress);

    m_shot = new QPushButton(tr("Save screenshot…"), panel);
    form->addRow(m_shot);

    m_status = new QLabel(panel);
    m_status->setWordWrap(true);
    form->addRow(m_status);

    auto* help = new QLabel(tr("Drag to orbit, wheel to zoom."), panel);
    help->setStyleSheet(QStringLiteral("color: gray"));
    form->addRow(help);
}

void MainWindow::connectControls()
{
    connect(m_compare, &QCheckBox::toggled, this, [this](bool on) {
        m_fabricB->setEnabled(on);
        m_viewB->setVisible(on);
        showChoices();
    });
    connect(m_garment, &QComboBox::currentIndexChanged, this, &MainWindow::showChoices);
    connect(m_fabricA, &QComboBox::currentIndexChanged, this, &MainWindow::showChoices);
    connect(m_fabricB, &QComboBox::currentIndexChanged, this, &MainWindow::showChoices);
    connect(m_drape, &QPushButton::clicked, this, [this] {
        QString err;
        if (!startDrape(&err)) showMessage(err);
    });
    connect(m_cancel, &QPushButton::clicked, this, [this] {
        m_viewA->cancel();
        m_viewB->cancel();
        m_fitJob.cancel();
    });
    connect(m_shot, &QPushButton::clicked, this, [this] {
        const QString path = QFileDialog::getSaveFileName(this, tr("Save screenshot"), QStringLiteral("fitting.png"),
                                                          tr("PNG images (*.png)"));
        QString err;
        if (!path.isEmpty() && !saveScreenshot(path, &err)) showMessage(err);
    });
    for (FittingView* v : {m_viewA, m_viewB}) {
        connect(v, &FittingView::drapeProgress, this, [this, v](double f, const QString& msg) {
            if (v == m_viewA || !m_viewA->busy()) {
                if (f < 0) m_progress->setRange(0, 0);
                else {
                    m_progress->setRange(0, 1000);
                    m_progress->setValue(int(1000 * f));
                }
            }
            m_status->setText(msg);
        });
        connect(v, &FittingView::finished, this, [this](bool ok, const QString& msg) {
            m_allOk = m_allOk && ok;
            m_lastMessage = msg;
            if (--m_pending <= 0) onViewFinished();
        });
    }
    connect(&m_fitJob, &widget::LongJob::progress, this, [this](double f, const QString& msg) {
        if (f < 0) m_progress->setRange(0, 0);
        else {
            m_progress->setRange(0, 1000);
            m_progress->setValue(int(1000 * f));
        }
        m_status->setText(msg);
    });
}

bool MainWindow::loadMannequin(const QString& path, QString* error)
{
    try {
        auto m = std::make_shared<importers::Mannequin>(importers::load_mannequin(path.toStdString(), importOptions(m_options)));
        m_mannequin = m;
        m_viewA->setMannequin(m);
        m_viewB->setMannequin(m);
        m_mannequinPath->setText(QFileInfo(path).fileName());
        m_mannequinPath->setToolTip(QStringLiteral("%1\n%2 vertices, %3 triangles, %4 m tall")
                                        .arg(path)
                                        .arg(m->mesh.vertex_count())
                                        .arg(m->mesh.triangle_count())
                                        .arg(m->height(), 0, 'f', 3));
        return true;
    } catch (const std::exception& e) {
        if (error) *error = QString::fromStdString(e.what());
        return false;
    }
}

void MainWindow::chooseMannequin()
{
    const QString path = QFileDialog::getOpenFileName(this, tr("Mannequin"), QString(),
                                                      tr("Meshes (*.obj *.dae *.zae *.gltf *.glb *.fbx *.ply *.stl);;All files (*)"));
    if (path.isEmpty()) return;
    QString err;
    if (!loadMannequin(path, &err)) QMessageBox::warning(this, tr("Mannequin"), err);
    else showChoices();
}

bool MainWindow::setGarmentFile(const QString& path, QString* error)
{
    if (!QFileInfo::exists(path)) {
        if (error) *error = tr("no such garment mesh: %1").arg(path);
        return false;
    }
    m_garmentFile = path;
    m_viewA->setGarmentMeshFile(path);
    m_viewB->setGarmentMeshFile(path);
    m_garment->setItemText(m_garment->findData(QStringLiteral("garment")), tr("Imported: %1").arg(QFileInfo(path).fileName()));
    return true;
}

void MainWindow::chooseGarmentFile()
{
    const QString path = QFileDialog::getOpenFileName(this, tr("Garment mesh"), QString(),
                                                      tr("Meshes (*.obj *.dae *.zae *.gltf *.glb *.fbx *.ply *.stl);;All files (*)"));
    QString err;
    if (!path.isEmpty() && !setGarmentFile(path, &err)) QMessageBox::warning(this, tr("Garment"), err);
}

void MainWindow::filterBrowser(const QString& text)
{
    for (int i = 0; i < m_browser->topLevelItemCount(); ++i) {
        QTreeWidgetItem* item = m_browser->topLevelItem(i);
        const std::size_t k = std::size_t(item->data(0, Qt::UserRole).toInt());
        const auto& f = m_fabrics[k];
        const QString hay = QString::fromStdString(f.name + " " + f.preset.composition + " " + f.preset.source + " " + f.origin);
        item->setHidden(!text.isEmpty() && !hay.contains(text, Qt::CaseInsensitive));
    }
}

void MainWindow::reloadFabrics(const QString& select)
{
    std::vector<std::string> warnings;
    m_fabrics = library::available_fabrics(m_options.library.toStdString(), m_options.starterDir.toStdString(), &warnings);
    m_browser->setSortingEnabled(false);
    m_browser->clear();
    for (std::size_t i = 0; i < m_fabrics.size(); ++i) {
        const auto& f = m_fabrics[i];
        auto* item = new QTreeWidgetItem(m_browser);
        item->setText(0, QString::fromStdString(f.name));
        item->setData(0, Qt::UserRole, int(i));
        item->setToolTip(0, f.preset.composition.empty() ? QString::fromStdString(f.name)
                                                         : QStringLiteral("%1\n%2").arg(QString::fromStdString(f.name), QString::fromStdString(f.preset.composition)));
        item->setData(1, Qt::DisplayRole, std::round(f.preset.params[cloth::Param::AreaDensity] * 1e4) / 10);
        if (f.preset.drape) item->setData(2, Qt::DisplayRole, std::round(f.preset.drape->percent * 10) / 10);
        item->setText(3, QString::fromStdString(f.origin));
    }
    m_browser->setSortingEnabled(true);
    filterBrowser(m_search->text());
    // Refilled without a scene per intermediate index: the view shows the choice once, below.
    const QSignalBlocker blockA(m_fabricA), blockB(m_fabricB);
    for (QComboBox* box : {m_fabricA, m_fabricB}) {
        const QString keep = select.isEmpty() ? box->currentText() : select;
        box->clear();
        for (const auto& f : m_fabrics)
            box->addItem(QStringLiteral("%1  (%2)").arg(QString::fromStdString(f.name), QString::fromStdString(f.origin)));
        const int i = keep.isEmpty() ? -1 : findFabric(keep.section(QStringLiteral("  ("), 0, 0));
        if (i >= 0) box->setCurrentIndex(i);
    }
    if (m_fabricB->count() > 1 && m_fabricB->currentIndex() == m_fabricA->currentIndex() && select.isEmpty())
        m_fabricB->setCurrentIndex(1);
    if (!warnings.empty()) showMessage(QString::fromStdString(warnings.front()));
    showChoices();
}

int MainWindow::findFabric(const QString& text) const
{
    for (std::size_t i = 0; i < m_fabrics.size(); ++i)
        if (QString::fromStdString(m_fabrics[i].name).compare(text, Qt::CaseInsensitive) == 0) return int(i);
    for (std::size_t i = 0; i < m_fabrics.size(); ++i)
        if (QString::fromStdString(m_fabrics[i].name).contains(text, Qt::CaseInsensitive)) return int(i);
    return -1;
}

bool MainWindow::draping() const
{
    return m_viewA->busy() || m_viewB->busy();
}

namespace {
GarmentChoice garmentOf(const QComboBox* box)
{
    const QString name = box->currentData().toString();
    return name == QLatin1String("tablecloth") ? GarmentChoice::Tablecloth
           : name == QLatin1String("garment")  ? GarmentChoice::Imported
                                               : GarmentChoice::Skirt;
}
} // namespace

void MainWindow::showChoices()
{
    if (draping() || m_fabrics.empty()) return;
    const GarmentChoice g = garmentOf(m_garment);
    const int a = m_fabricA->currentIndex();
    if (a >= 0 && a < int(m_fabrics.size())) m_viewA->showUndraped(g, m_fabrics[std::size_t(a)]);
    const int b = m_fabricB->currentIndex();
    if (m_compare->isChecked() && b >= 0 && b < int(m_fabrics.size())) m_viewB->showUndraped(g, m_fabrics[std::size_t(b)]);
}

bool MainWindow::startDrape(QString* error)
{
    if (draping() || m_fitJob.running()) {
        if (error) *error = tr("busy: wait for the running job or cancel it");
        return false;
    }
    const int a = m_fabricA->currentIndex();
    if (a < 0 || a >= int(m_fabrics.size())) {
        if (error) *error = tr("no fabric chosen");
        return false;
    }
    const GarmentChoice g = garmentOf(m_garment);
    m_allOk = true;
    m_pending = 0;
    if (!m_viewA->drape(g, m_fabrics[std::size_t(a)], error)) return false;
    ++m_pending;
    if (m_compare->isChecked()) {
        const int b = m_fabricB->currentIndex();
        if (b >= 0 && b < int(m_fabrics.size())) {
            if (!m_viewB->drape(g, m_fabrics[std::size_t(b)], error)) {
                m_viewA->cancel();
                return false;
            }
            ++m_pending;
        }
    }
    setBusy(true);
    m_status->setText(tr("Draping…"));
    return true;
}

void MainWindow::onViewFinished()
{
    setBusy(false);
    QString text = m_lastMessage;
    if (m_viewA->garment() != GarmentChoice::Tablecloth && m_viewA->mannequin() && m_allOk) {
        const importers::Penetration p = importers::body_penetration(*m_viewA->mannequin(), m_viewA->lastPositions());
        text += tr("; closest cloth vertex %1 mm from the body").arg(p.min_distance * 1000, 0, 'f', 1);
    }
    m_status->setText(text);
    m_progress->setRange(0, 1000);
    m_progress->setValue(m_allOk ? 1000 : 0);
    emit drapeFinished(m_allOk, m_lastMessage);
}

void MainWindow::setBusy(bool busy)
{
    m_drape->setEnabled(!busy);
    m_cancel->setEnabled(busy);
    m_fit->setEnabled(!busy);
    m_garment->setEnabled(!busy);
    m_browser->setEnabled(!busy);
}

void MainWindow::showMessage(const QString& text)
{
    m_status->setText(text);
    statusBar()->showMessage(text, 10000);
}

void MainWindow::fitFromRecord()
{
    const QString dir = QFileDialog::getExistingDirectory(this, tr("Drape-test record folder (one record, or records of one fabric)"),
                                                          QStringLiteral(DRAPE_SHARED_DIR "/data/drape-lab"));
    if (dir.isEmpty()) return;
    QString err;
    if (!fitRecords(dir, &err)) QMessageBox::warning(this, tr("Fit"), err);
}

namespace {
/// What the fit job hands back: the preset's JSON and the predictions of the
/// standard set-ups.
struct FitOutcome {
    nlohmann::json preset;
    struct Row {
        double d1 = 0, d2 = 0;   ///< the set-up [m]
        bool fitted = false;     ///< one of the fitted records' set-ups
        double dc = 0, lo = 0, hi = 0;
        int nodes = 0, nodes_lo = 0, nodes_hi = 0;
    };
    std::vector<Row> rows;
};

/// The drapemeter's standard set-ups (Cusick; ISO 9073-9 uses 300 / 180 mm; the
/// drape lab 240 / 180, 300 / 150 and 360 / 180 mm) [m].
constexpr double kStandardSetups[][2] = {{0.24, 0.18}, {0.30, 0.15}, {0.36, 0.18}};
} // namespace

bool MainWindow::fitRecords(const QString& dir, QString* error)
{
    namespace fs = std::filesystem;
    std::vector<estimate::MeasuredDrape> records;
    try {
        const fs::path p(dir.toStdString());
        if (!fs::is_directory(p)) throw std::runtime_error(dir.toStdString() + ": no such folder (a record folder, or a folder of one fabric's records)");
        if (fs::exists(p / "meta.json")) records.push_back(estimate::load_record(p.string()));
        else
            for (const auto& e : fs::directory_iterator(p))
                if (e.is_directory() && fs::exists(e.path() / "meta.json")) records.push_back(estimate::load_record(e.path().string()));
        if (records.empty()) throw std::runtime_error(dir.toStdString() + ": no record (meta.json) in this folder or its subfolders");
    } catch (const std::exception& e) {
        if (error) *error = QString::fromStdString(e.what());
        return false;
    }
    auto outcome = std::make_shared<FitOutcome>();
    setBusy(true);
    m_cancel->setEnabled(true);
    m_predictions->setVisible(false);
    const bool started = m_fitJob.start(tr("fit"), [records, outcome](widget::JobContext& ctx) {
        // `drape fit`'s defaults (the lab's laying and waviness, the drapes from flat
        // at grid 61 and the calibration from flat included: the same preset as the CLI's).
        estimate::FitOptions o = estimate::drape_fit_defaults();
        o.cancel = ctx.cancelFlag();
        o.progress = [&ctx](const estimate::FitProgress& p) {
            // A busy bar: the fit's length is not known ahead (estimate::fit_progress_line).
            ctx.report(-1.0, QStringLiteral("fit: ") + QString::fromStdString(estimate::fit_progress_line(p)));
        };
        const estimate::FitResult r = estimate::fit_fabric(records, o);
        if (r.cancelled) throw std::runtime_error("cancelled");
        outcome->preset = estimate::fit_to_json(r);
        // The standard set-ups the records did not cover, predicted as `drape predict`
        // does (two drapes each, to keep it short; the CLI draws three).
        const fabric::FabricPreset preset = fabric::fabric_from_json(outcome->preset, "fit");
        for (const auto& su : kStandardSetups) {
            FitOutcome::Row row;
            row.d1 = su[0];
            row.d2 = su[1];
            for (const auto& rec : records)
                row.fitted = row.fitted || (std::abs(rec.sample_diameter - su[0]) < 1e-4 && std::abs(rec.disc_diameter - su[1]) < 1e-4);
            cloth::DrapeSetup s;
            s.sample_diameter = su[0];
            s.disc_diameter = su[1];
            s.grid = 0;
            ctx.report(-1.0, QStringLiteral("predicting %1 / %2 mm").arg(su[0] * 1e3).arg(su[1] * 1e3));
            estimate::PredictOptions po;
            po.seeds = 2;
            po.cancel = ctx.cancelFlag();
            const estimate::Prediction pr = estimate::predict_drape(preset, estimate::prediction_setup(preset, s), po);
            if (ctx.cancelled()) throw std::runtime_error("cancelled");
            row.dc = pr.dc_percent;
            row.lo = pr.dc_lower95;
            row.hi = pr.dc_upper95;
            row.nodes = pr.node_count;
            row.nodes_lo = pr.nodes_lower;
            row.nodes_hi = pr.nodes_upper;
            outcome->rows.push_back(row);
        }
    });
    if (!started) {
        setBusy(false);
        if (error) *error = tr("another fit is running");
        return false;
    }
    connect(&m_fitJob, &widget::LongJob::finished, this, [this, outcome, records](bool ok, const QString& msg) {
        setBusy(false);
        // The fit's bar was a busy bar (no fraction of a fit is known ahead): stop it.
        m_progress->setRange(0, 1000);
        m_progress->setValue(ok ? 1000 : 0);
        if (!ok) {
            showMessage(tr("Fit: %1").arg(msg));
            emit fitFinished(false, msg);
            return;
        }
        // One record: its id. Several (one fabric's set-ups): what their ids share up to a
        // separator ("DL-D1-300-150", "DL-D1-360-180" -> "DL-D1"), else the first id.
        std::string stem = records.front().id;
        for (const auto& rec : records) {
            std::size_t n = 0;
            while (n < stem.size() && n < rec.id.size() && stem[n] == rec.id[n]) ++n;
            stem.resize(n);
        }
        if (records.size() > 1) {
            while (!stem.empty() && std::isalnum(static_cast<unsigned char>(stem.back()))) stem.pop_back();
            while (!stem.empty() && !std::isalnum(static_cast<unsigned char>(stem.back()))) stem.pop_back();
        }
        if (stem.empty()) stem = records.front().id;
        QString name = QString::fromStdString(stem) + tr(" (fitted)");
        try {
            fabric::FabricPreset preset = fabric::fabric_from_json(outcome->preset, "fit of " + records.front().source);
            preset.name = name.toStdString();
            const std::string path =
                m_options.library.isEmpty() ? library::default_library_path() : m_options.library.toStdString();
            library::FabricLibrary lib(path);
            lib.import_preset(fabric::fabric_to_json(preset), "fit", name.toStdString(), library::OnConflict::Rename);
            reloadFabrics(name);
            showMessage(tr("Fitted fabric added to the library %1").arg(QString::fromStdString(path)));
        } catch (const std::exception& e) {
            showMessage(tr("Fit: %1").arg(QString::fromStdString(e.what())));
            emit fitFinished(false, QString::fromStdString(e.what()));
            return;
        }
        QString html = tr("<b>%1</b>: the drape it predicts (95 % interval)").arg(name.toHtmlEscaped());
        html += QStringLiteral("<table cellspacing=\"4\"><tr><th align=\"left\">%1</th><th>D [%]</th><th>folds</th></tr>").arg(tr("set-up [mm]"));
        for (const auto& r : outcome->rows) {
            const QString setup = QStringLiteral("%1 / %2").arg(r.d1 * 1e3, 0, 'f', 0).arg(r.d2 * 1e3, 0, 'f', 0);
            html += QStringLiteral("<tr><td>%1%2</td><td>%3 (%4..%5)</td><td>%6 (%7..%8)</td></tr>")
                        .arg(setup, r.fitted ? tr(" fitted") : QString())
                        .arg(r.dc, 0, 'f', 1)
                        .arg(r.lo, 0, 'f', 0)
                        .arg(r.hi, 0, 'f', 0)
                        .arg(r.nodes)
                        .arg(r.nodes_lo)
                        .arg(r.nodes_hi);
        }
        html += QStringLiteral("</table>");
        std::vector<std::pair<long, long>> setups;
        for (const auto& rec : records) {
            const std::pair<long, long> k{std::lround(rec.sample_diameter * 1e4), std::lround(rec.disc_diameter * 1e4)};
            if (std::find(setups.begin(), setups.end(), k) == setups.end()) setups.push_back(k);
        }
        if (setups.size() < 2)
            html += tr("<i>Fitted on one set-up: a preset predicts other set-ups poorly from one drape. Drape the same specimen "
                       "once more at a second set-up and fit a folder holding both records: the intervals above narrow.</i>");
        m_predictions->setText(html);
        m_predictions->setVisible(true);
        emit fitFinished(true, name);
    }, Qt::SingleShotConnection);
    return true;
}

QImage MainWindow::screenshot()
{
    const QImage a = m_viewA->grabFrame();
    if (!m_compare->isChecked() || !m_viewB->isVisible()) return a;
    const QImage b = m_viewB->grabFrame();
    QImage out(a.width() + b.width() + 4, std::max(a.height(), b.height()), QImage::Format_RGB32);
    out.fill(QColor(0x20, 0x20, 0x20));
    QPainter p(&out);
    p.drawImage(0, 0, a);
    p.drawImage(a.width() + 4, 0, b);
    return out;
}

bool MainWindow::saveScreenshot(const QString& path, QString* error)
{
    const QImage img = screenshot();
    if (img.isNull() || !img.save(path)) {
        if (error) *error = tr("cannot write the screenshot %1").arg(path);
        return false;
    }
    return true;
}

QByteArray MainWindow::summaryJson() const
{
    QJsonObject root;
    QJsonArray views;
    for (FittingView* v : {m_viewA, m_viewB}) {
        const widget::DrapeMeshPtr mesh = v->controller()->currentMesh();
        if (!mesh || !v->lastResults() || (v == m_viewB && !m_compare->isChecked())) continue;
        QJsonObject o;
        const cloth::SolverStatus st = v->lastStatus();
        o["garment"] = toString(v->garment());
        o["fabric"] = v->fabricName();
        o["vertices"] = mesh->vertexCount;
        o["triangles"] = int(mesh->F.rows());
        o["outcome"] = QString::fromStdString(cloth::to_string(st.outcome));
        o["newton_iterations"] = double(st.newton_iterations);
        o["residual"] = st.residual;
        o["wall_seconds"] = st.wall_seconds;
        const cloth::Positions x = v->lastPositions();
        if (mesh->body && x.rows() > 0) {
            const importers::Penetration p = importers::body_penetration(*mesh->body, x);
            o["min_body_distance_m"] = p.min_distance;
            o["vertices_inside_body"] = p.inside;
            if (v->garment() == GarmentChoice::Skirt) {
                const importers::Girth waist = importers::find_waist(*mesh->body);
                o["waist_z_m"] = waist.z;
                o["waist_radius_m"] = waist.max_radius;
            }
            const auto& b = mesh->body->bounds;
            o["mannequin_bounding_box_m"] = QJsonObject{
                {"min", QJsonArray{b.min.x(), b.min.y(), b.min.z()}},
                {"max", QJsonArray{b.max.x(), b.max.y(), b.max.z()}}};
        }
        if (x.rows() > 0) {
            o["cloth_min_z_m"] = x.col(2).minCoeff();
            o["cloth_max_z_m"] = x.col(2).maxCoeff();
        }
        views.append(o);
    }
    root["views"] = views;
    return QJsonDocument(root).toJson();
}

void MainWindow::runScript(const ScriptOptions& s)
{
    auto fail = [this](const QString& msg) {
        qCritical("drape-demo: %s", qPrintable(msg));
        QTimer::singleShot(0, this, [this] { emit scriptFinished(1); });
    };
    const int gi = m_garment->findData(s.garment);
    if (gi < 0) return fail(tr("unknown garment \"%1\" (expected skirt, tablecloth or garment)").arg(s.garment));
    m_garment->setCurrentIndex(gi);
    if (!s.garmentFile.isEmpty()) {
        QString err;
        if (!setGarmentFile(s.garmentFile, &err)) return fail(err);
    }
    if (!s.fabric.isEmpty()) {
        const int i = findFabric(s.fabric);
        if (i < 0) return fail(tr("no fabric matches \"%1\"").arg(s.fabric));
        m_fabricA->setCurrentIndex(i);
    }
    if (!s.fabric2.isEmpty()) {
        const int i = findFabric(s.fabric2);
        if (i < 0) return fail(tr("no fabric matches \"%1\"").arg(s.fabric2));
        m_compare->setChecked(true);
        m_fabricB->setCurrentIndex(i);
    }
    connect(this, &MainWindow::drapeFinished, this, [this, s](bool ok, const QString& msg) {
        qInfo("drape-demo: %s", qPrintable(msg));
        int code = ok ? 0 : 1;
        if (!s.screenshot.isEmpty()) {
            QString err;
            if (!saveScreenshot(s.screenshot, &err)) {
                qCritical("drape-demo: %s", qPrintable(err));
                code = 1;
            } else
                qInfo("drape-demo: wrote %s", qPrintable(s.screenshot));
        }
        const QByteArray summary = summaryJson();
        if (!s.json.isEmpty()) {
            QFile f(s.json);
            if (f.open(QIODevice::WriteOnly)) f.write(summary);
            else code = 1;
        }
        fputs(summary.constData(), stdout);
        emit scriptFinished(code);
    }, Qt::SingleShotConnection);
    QString err;
    if (!startDrape(&err)) return fail(err);
}

} // namespace drape::demo
