#include "widget/long_job.hpp"

#include <QMetaObject>
#include <QPointer>
#include <QThread>

#include <exception>
#include <memory>

namespace drape::widget {

void JobContext::report(double fraction, const QString& message)
{
    if (LongJob* owner = m_owner)
        QMetaObject::invokeMethod(owner, [owner, fraction, message] { emit owner->progress(fraction, message); },
                                  Qt::QueuedConnection);
}

LongJob::LongJob(QObject* parent) : QObject(parent) {}

LongJob::~LongJob()
{
    if (m_thread) {
        m_ctx->m_cancel = true;
        m_ctx->m_owner = nullptr;
        m_thread->wait();
        delete m_thread;
        delete m_ctx;
    }
}

bool LongJob::start(const QString& name, JobFunction fn)
{
    if (m_thread || !fn) return false;
    m_name = name;
    m_ctx = new JobContext;
    m_ctx->m_owner = this;
    auto result = std::make_shared<std::pair<bool, QString>>(true, QString());
    JobContext* ctx = m_ctx;
    m_thread = QThread::create([fn = std::move(fn), ctx, result] {
        try {
            fn(*ctx);
            if (ctx->cancelled()) *result = {false, QStringLiteral("cancelled")};
        } catch (const std::exception& e) {
            *result = {false, QString::fromUtf8(e.what())};
        } catch (...) {
            *result = {false, QStringLiteral("unknown error")};
        }
    });
    connect(m_thread, &QThread::finished, this, [this, result] {
        m_thread->deleteLater();
        m_thread = nullptr;
        delete m_ctx;
        m_ctx = nullptr;
        emit finished(result->first, result->first ? QStringLiteral("done") : result->second);
    });
    emit started(name);
    m_thread->start();
    return true;
}

void LongJob::cancel()
{
    if (m_ctx) m_ctx->m_cancel = true;
}

} // namespace drape::widget
