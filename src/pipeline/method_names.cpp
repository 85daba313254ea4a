// The names of contour()'s enums, as the CLI and Python spell them (pipeline.h).
#include "pipeline/enum_names.h"
#include "sdfcontour/pipeline/pipeline.h"

namespace sdfcontour {

namespace {
const detail::NameTable<Method> kMethods = {{"gcp", Method::Gcp},
                                            {"gtcp", Method::Gtcp},
                                            {"mc", Method::Mc},
                                            {"mt-rt", Method::MtRt},
                                            {"mt-dt", Method::MtDt}};
const detail::NameTable<GradientSource> kGradientSources = {{"auto", GradientSource::Auto},
                                                            {"regular", GradientSource::Regular},
                                                            {"delaunay", GradientSource::Delaunay},
                                                            {"knn", GradientSource::Knn},
                                                            {"lattice", GradientSource::Lattice}};
const detail::NameTable<Reconstruction> kReconstructions = {{"auto", Reconstruction::Auto},
                                                            {"poisson", Reconstruction::Poisson},
                                                            {"local", Reconstruction::Local}};
const detail::NameTable<Switch> kSwitches = {
    {"auto", Switch::Auto}, {"on", Switch::On}, {"off", Switch::Off}};
}  // namespace

Switch parse_switch(const std::string& what, const std::string& name) {
  return detail::parse_name(kSwitches, what, name);
}

Reconstruction parse_reconstruction(const std::string& name) {
  return detail::parse_name(kReconstructions, "reconstruction", name);
}
std::string reconstruction_name(Reconstruction reconstruction) {
  return detail::name_of(kReconstructions, reconstruction);
}

Method parse_method(const std::string& name) {
  return detail::parse_name(kMethods, "method", name);
}
std::string method_name(Method method) {
  return detail::name_of(kMethods, method);
}
GradientSource parse_gradient_source(const std::string& name) {
  return detail::parse_name(kGradientSources, "gradient source", name);
}
std::string gradient_source_name(GradientSource source) {
  return detail::name_of(kGradientSources, source);
}

}  // namespace sdfcontour
