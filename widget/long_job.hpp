#pragma once
// A generic long job (e.g. fitting a fabric preset to a record) run off the GUI
// thread with progress and cancel. The estimator plugs its work in as a
// function; the widget shows progress and offers cancel, and whatever the job
// throws becomes a finished(false, message) signal instead of a crash.
#include "widget/drape_widget_export.hpp"
#include <QObject>
#include <QString>

#include <atomic>
#include <functional>

class QThread;

namespace drape::widget {

/// Handed to the job function (on the job's thread).
class DRAPE_WIDGET_EXPORT JobContext {
public:
    /// Reports progress: fraction in [0, 1] (negative = unknown) and a message. Thread-safe.
    void report(double fraction, const QString& message);
    bool cancelled() const { return m_cancel.load(); }
    /// For APIs that poll a flag (RestOptions::cancel and the estimator's options).
    const std::atomic<bool>* cancelFlag() const { return &m_cancel; }

private:
    friend class LongJob;
    std::atomic<bool> m_cancel{false};
    class LongJob* m_owner = nullptr;
};

using JobFunction = std::function<void(JobContext&)>;

class DRAPE_WIDGET_EXPORT LongJob : public QObject {
    Q_OBJECT
public:
    explicit LongJob(QObject* parent = nullptr);
    ~LongJob() override; ///< cancels and waits for a running job

    /// Starts `fn` on a new thread. Returns false (and emits nothing) when a job is running.
    bool start(const QString& name, JobFunction fn);
    void cancel();
    bool running() const { return m_thread != nullptr; }
    QString name() const { return m_name; }

signals:
    void started(const QString& name);
    void progress(double fraction, const QString& message);
    /// ok = the function returned without throwing and was not cancelled.
    void finished(bool ok, const QString& message);

private:
    friend class JobContext;
    QThread* m_thread = nullptr;
    JobContext* m_ctx = nullptr;
    QString m_name;
};

} // namespace drape::widget
