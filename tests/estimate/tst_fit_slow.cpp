#include <QTest>
class TestFitSlow : public QObject { Q_OBJECT private slots: void placeholder() { QSKIP("written below"); } };
QTEST_APPLESS_MAIN(TestFitSlow)
#include "tst_fit_slow.moc"
