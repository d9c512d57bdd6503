#pragma once
// The demo app for fittings: choose a mannequin, a garment (the circle skirt,
// the tablecloth, or an imported garment mesh) and a fabric (from the library
// browser - search, weight, drape coefficient - or fitted now from a drape-test
// record into the library), drape it, orbit, compare two fabrics side by side,
// save a screenshot. Each view is the widget library's DrapeView.
// A scripted mode runs one fitting without a user (for Xvfb, tests and docs).
#include "demo/fitting_view.hpp"

#include "widget/long_job.hpp"

#include <QMainWindow>
#include <QString>

#include <memory>
#include <vector>

class QCheckBox;
class QComboBox;
class QFormLayout;
class QLabel;
class QLineEdit;
class QProgressBar;
class QPushButton;
class QSplitter;
class QTreeWidget;

namespace drape::demo {

struct DemoOptions {
    QString mannequin;      ///< empty = default_mannequin_path()
    QString unit = "file";  ///< mannequin unit: file|mm|cm|m
    QString up = "file";    ///< mannequin up axis: file|y|z
    QString library;        ///< fabric library path, empty = default
    QString starterDir;     ///< starter presets folder, empty = the source tree's data/library
};

/// What a scripted run does.
struct ScriptOptions {
    QString garment = "skirt"; ///< skirt | tablecloth | garment (with garmentFile)
    QString garmentFile;       ///< an imported garment mesh (its top boundary is pinned)
    QString fabric;            ///< fabric name (substring match), empty = the first one
    QString fabric2;           ///< second fabric: compare side by side
    QString screenshot;        ///< PNG path
    QString json;              ///< summary JSON path (optional)
};

class MainWindow : public QMainWindow {
    Q_OBJECT
public:
    explicit MainWindow(const DemoOptions& options, QWidget* parent = nullptr);
    ~MainWindow() override;

    /// Loads the mannequin; false (and an error message) when it cannot.
    bool loadMannequin(const QString& path, QString* error = nullptr);
    const std::vector<library::FabricChoice>& fabrics() const { return m_fabrics; }
    /// Index of the first fabric whose name contains `text` (case-insensitive), -1 if none.
    int findFabric(const QString& text) const;

    /// Starts the drape of the current choices in one or both views.
    bool startDrape(QString* error = nullptr);
    /// Shows the current choices undraped in the view(s) (the skirt's pattern on
    /// the mannequin, the flat tablecloth), as the window opens and when a
    /// choice changes while nothing drapes.
    void showChoices();
    bool draping() const;
    /// The view(s) as one image (side by side when comparing).
    QImage screenshot();
    bool saveScreenshot(const QString& path, QString* error = nullptr);

    /// Runs a scripted fitting; emits scriptFinished(exitCode) when done.
    void runScript(const ScriptOptions& s);

    FittingView* viewA() const { return m_viewA; }
    FittingView* viewB() const { return m_viewB; }
    QComboBox* garmentBox() const { return m_garment; }
    /// The library browser: every fabric with its weight and drape coefficient, filtered by the search text.
    QTreeWidget* fabricBrowser() const { return m_browser; }
    QLineEdit* fabricSearch() const { return m_search; }
    /// Imports a garment mesh for the "Imported garment" choice; false (and a message) when it cannot.
    bool setGarmentFile(const QString& path, QString* error = nullptr);
    QComboBox* fabricBoxA() const { return m_fabricA; }
    QComboBox* fabricBoxB() const { return m_fabricB; }
    QCheckBox* compareBox() const { return m_compare; }
    QPushButton* fitButton() const { return m_fit; }
    QProgressBar* progressBar() const { return m_progress; }
    /// Summary of the last drape of view A (and B) as JSON text.
    QByteArray summaryJson() const;
    /// Fits a fabric to the records in `dir` (one record folder, or a folder of
    /// records of one fabric, e.g. two set-ups), adds it to the library, and
    /// predicts the drapemeter's standard set-ups it was not fitted on (with
    /// their 95 % intervals, shown under the fit button). Emits fitFinished.
    /// False (and a message) when the folder holds no record.
    bool fitRecords(const QString& dir, QString* error = nullptr);
    /// The predictions of the last fit (rich text; empty before one).
    QLabel* predictionsLabel() const { return m_predictions; }

signals:
    void drapeFinished(bool ok, const QString& message);
    void scriptFinished(int exitCode);
    void fitFinished(bool ok, const QString& message);

private:
    void buildUi();
    /// The library browser: the search field and the list (weight, D, source).
    void addLibraryBrowser(QWidget* panel, QFormLayout* form);
    /// Fit, its predictions, Drape / Cancel, the progress, the screenshot and the status.
    void addActions(QWidget* panel, QFormLayout* form);
    /// The controls' and the views' signals.
    void connectControls();
    void reloadFabrics(const QString& select = {});
    void filterBrowser(const QString& text);
    void chooseGarmentFile();
    void onViewFinished();
    void fitFromRecord();
    void chooseMannequin();
    void setBusy(bool busy);
    void showMessage(const QString& text);

    DemoOptions m_options;
    std::shared_ptr<const importers::Mannequin> m_mannequin;
    std::vector<library::FabricChoice> m_fabrics;
    FittingView* m_viewA = nullptr;
    FittingView* m_viewB = nullptr;
    QSplitter* m_split = nullptr;
    QLineEdit* m_mannequinPath = nullptr;
    QComboBox* m_garment = nullptr;
    QLineEdit* m_search = nullptr;
    QTreeWidget* m_browser = nullptr;
    QString m_garmentFile;
    QComboBox* m_fabricA = nullptr;
    QComboBox* m_fabricB = nullptr;
    QCheckBox* m_compare = nullptr;
    QPushButton* m_drape = nullptr;
    QPushButton* m_cancel = nullptr;
    QPushButton* m_fit = nullptr;
    QPushButton* m_shot = nullptr;
    QProgressBar* m_progress = nullptr;
    QLabel* m_status = nullptr;
    QLabel* m_predictions = nullptr;
    widget::LongJob m_fitJob;
    int m_pending = 0;  ///< views still draping
    bool m_allOk = true;
    QString m_lastMessage;
};

} // namespace drape::demo
