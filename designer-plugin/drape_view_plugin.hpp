#pragma once
// Qt Designer custom-widget plugin for drape::widget::DrapeView. Everything
// real lives in the drape_widget library; this only describes the widget to
// Designer and QUiLoader (name, group, icon, default properties).
#include <QObject>
#include <QtUiPlugin/QDesignerCustomWidgetInterface>

class DrapeViewPlugin : public QObject, public QDesignerCustomWidgetInterface {
    Q_OBJECT
    Q_PLUGIN_METADATA(IID "org.qt-project.Qt.QDesignerCustomWidgetInterface")
    Q_INTERFACES(QDesignerCustomWidgetInterface)

public:
    explicit DrapeViewPlugin(QObject* parent = nullptr);

    QString name() const override;
    QString group() const override;
    QString toolTip() const override;
    QString whatsThis() const override;
    QString includeFile() const override;
    QIcon icon() const override;
    bool isContainer() const override;
    QWidget* createWidget(QWidget* parent) override;
    bool isInitialized() const override;
    void initialize(QDesignerFormEditorInterface* core) override;
    QString domXml() const override;

private:
    bool m_initialized = false;
};
