#include "drape_view_plugin.hpp"

#include "widget/drape_view.hpp"

#include <QPainter>
#include <QPainterPath>
#include <QPixmap>

DrapeViewPlugin::DrapeViewPlugin(QObject* parent) : QObject(parent) {}

QString DrapeViewPlugin::name() const
{
    return QStringLiteral("drape::widget::DrapeView");
}

QString DrapeViewPlugin::group() const
{
    return QStringLiteral("Drapekit");
}

QString DrapeViewPlugin::toolTip() const
{
    return QStringLiteral("Cloth drape simulation (Qt Quick 3D): the drapemeter, garments on bodies, library fabrics");
}

QString DrapeViewPlugin::whatsThis() const
{
    return QStringLiteral("DrapeView simulates a fabric preset draping over the drapemeter pedestal, "
                          "with pinning, timing, texture and the lab's camera views.");
}

QString DrapeViewPlugin::includeFile() const
{
    return QStringLiteral("widget/drape_view.hpp");
}

QIcon DrapeViewPlugin::icon() const
{
    // Drawn rather than shipped as a file: a grey pedestal under a red drape with folds.
    QPixmap pm(64, 64);
    pm.fill(Qt::transparent);
    QPainter p(&pm);
    p.setRenderHint(QPainter::Antialiasing);
    p.setPen(Qt::NoPen);
    p.setBrush(QColor(0x80, 0x80, 0x80));
    p.drawRect(24, 30, 16, 30);
    QPainterPath cloth;
    cloth.moveTo(20, 14);
    cloth.lineTo(44, 14);
    cloth.cubicTo(52, 20, 58, 34, 60, 46);
    cloth.quadTo(55, 40, 52, 48);
    cloth.quadTo(48, 40, 44, 46);
    cloth.lineTo(20, 46);
    cloth.quadTo(16, 40, 12, 48);
    cloth.quadTo(9, 40, 4, 46);
    cloth.cubicTo(6, 34, 12, 20, 20, 14);
    p.setBrush(QColor(0xb0, 0x3a, 0x48));
    p.drawPath(cloth);
    p.setBrush(QColor(0xd8, 0x6a, 0x76));
    p.drawEllipse(QRectF(20, 10, 24, 8));
    return QIcon(pm);
}

bool DrapeViewPlugin::isContainer() const
{
    return false;
}

QWidget* DrapeViewPlugin::createWidget(QWidget* parent)
{
    return new drape::widget::DrapeView(parent);
}

bool DrapeViewPlugin::isInitialized() const
{
    return m_initialized;
}

void DrapeViewPlugin::initialize(QDesignerFormEditorInterface*)
{
    m_initialized = true;
}

QString DrapeViewPlugin::domXml() const
{
    // Defaults for a new form: the lab's 300/150 mm set-up on a light 30-node
    // grid that drapes in a few seconds, running, seen from the iso direction at 0.6 m.
    return QStringLiteral(R"(<ui language="c++" displayname="DrapeView">
 <widget class="drape::widget::DrapeView" name="drapeView">
  <property name="geometry"><rect><x>0</x><y>0</y><width>480</width><height>360</height></rect></property>
  <property name="sampleDiameter"><double>300.0</double></property>
  <property name="discDiameter"><double>150.0</double></property>
  <property name="gridSize"><number>30</number></property>
  <property name="integrator"><enum>drape::widget::Drape::Symplectic</enum></property>
  <property name="viewPreset"><enum>drape::widget::Drape::Close</enum></property>
  <property name="running"><bool>true</bool></property>
 </widget>
 <customwidgets>
  <customwidget>
   <class>drape::widget::DrapeView</class>
   <extends>QWidget</extends>
   <header>widget/drape_view.hpp</header>
  </customwidget>
 </customwidgets>
</ui>
)");
}
