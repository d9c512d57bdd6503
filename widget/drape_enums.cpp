#include "widget/drape_enums.hpp"

#include <array>
#include <utility>

namespace drape::widget {

namespace {

template <class E, std::size_t N>
std::optional<E> lookup(const std::array<std::pair<E, const char*>, N>& table, const QString& name)
{
    for (const auto& [value, text] : table)
        if (name.compare(QLatin1String(text), Qt::CaseInsensitive) == 0) return value;
    return std::nullopt;
}

template <class E, std::size_t N>
QString name(const std::array<std::pair<E, const char*>, N>& table, E value)
{
    for (const auto& [v, text] : table)
        if (v == value) return QString::fromLatin1(text);
    return {};
}

const std::array<std::pair<Drape::Integrator, const char*>, 6> kIntegrators{{{Drape::Symplectic, "symplectic"},
                                                                             {Drape::Euler, "euler"},
                                                                             {Drape::Midpoint, "midpoint"},
                                                                             {Drape::RK4, "rk4"},
                                                                             {Drape::Implicit, "implicit"},
                                                                             {Drape::Static, "static"}}};
const std::array<std::pair<Drape::ViewPreset, const char*>, 5> kViews{
    {{Drape::Top, "top"}, {Drape::Side, "side"}, {Drape::Iso, "iso"}, {Drape::Close, "close"}, {Drape::Free, "free"}}};
const std::array<std::pair<Drape::ClothShape, const char*>, 5> kShapes{{{Drape::Disc, "disc"},
                                                                        {Drape::Square, "square"},
                                                                        {Drape::Skirt, "skirt"},
                                                                        {Drape::Tablecloth, "tablecloth"},
                                                                        {Drape::GarmentMesh, "garment"}}};

} // namespace

cloth::Integrator toEngine(Drape::Integrator i)
{
    switch (i) {
    case Drape::Symplectic: return cloth::Integrator::SemiImplicitEuler;
    case Drape::Euler: return cloth::Integrator::ExplicitEuler;
    case Drape::Midpoint: return cloth::Integrator::Midpoint;
    case Drape::RK4: return cloth::Integrator::RK4;
    case Drape::Implicit: return cloth::Integrator::ImplicitEuler;
    case Drape::Static: return cloth::Integrator::Static;
    }
    return cloth::Integrator::SemiImplicitEuler;
}

QString toString(Drape::Integrator i) { return name(kIntegrators, i); }
QString toString(Drape::ViewPreset v) { return name(kViews, v); }
QString toString(Drape::ClothShape s) { return name(kShapes, s); }
std::optional<Drape::Integrator> parseIntegrator(const QString& n) { return lookup(kIntegrators, n); }
std::optional<Drape::ViewPreset> parseViewPreset(const QString& n) { return lookup(kViews, n); }
std::optional<Drape::ClothShape> parseClothShape(const QString& n) { return lookup(kShapes, n); }

} // namespace drape::widget
