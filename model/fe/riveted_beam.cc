#include "jointlab/model/fe/riveted_beam.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <map>
#include <optional>
#include <set>
#include <string>

#include <fmt/format.h>
#include <toml++/toml.h>

#include "jointlab/core/error.h"
#include "jointlab/data/csv_lines.h"
#include "jointlab/model/fe/strip_mesh.h"
#include "jointlab/model/iwan.h"

namespace jointlab::model::fe {
namespace {

// Reading context: the file name for messages.
struct Reader {
  std::string file;

  [[noreturn]] void fail(const toml::node* node, const std::string& message) const {
    const long line = node ? static_cast<long>(node->source().begin.line) : 0;
    throw InputError(where(file, line, message));
  }

  void reject_unknown(const toml::table& t, const std::string& name,
                      const std::set<std::string>& known) const {
    for (const auto& [key, value] : t)
      if (!known.count(std::string(key.str())))
        fail(&value,
             fmt::format("unknown field '{}{}'", name.empty() ? "" : name + ".", key.str()));
  }

  const toml::table* table(const toml::table& doc, const std::string& name) const {
    const toml::node* n = doc.get(name);
    if (!n) return nullptr;
    if (!n->is_table()) fail(n, fmt::format("'{}' must be a table [{}]", name, name));
    return n->as_table();
  }

  std::optional<double> number(const toml::table* t, const std::string& tname,
                               const std::string& key) const {
    if (!t) return std::nullopt;
    const toml::node* n = t->get(key);
    if (!n) return std::nullopt;
    if (const auto v = n->value<double>(); v && (n->is_floating_point() || n->is_integer()))
      return *v;
    fail(n, fmt::format("field '{}.{}' must be a number", tname, key));
  }

  std::optional<long> integer(const toml::table* t, const std::string& tname,
                              const std::string& key) const {
    if (!t) return std::nullopt;
    const toml::node* n = t->get(key);
    if (!n) return std::nullopt;
    if (!n->is_integer()) fail(n, fmt::format("field '{}.{}' must be an integer", tname, key));
    return static_cast<long>(*n->value<int64_t>());
  }
};

int component_number(const Reader& r, const toml::node& n, const std::string& field) {
  static const std::map<std::string, int> names = {{"x", 1},  {"y", 2},  {"z", 3},
                                                   {"rx", 4}, {"ry", 5}, {"rz", 6}};
  if (n.is_integer()) {
    const auto v = *n.value<int64_t>();
    if (v >= 1 && v <= 6) return static_cast<int>(v);
  } else if (n.is_string()) {
    const auto it = names.find(*n.value<std::string>());
    if (it != names.end()) return it->second;
  }
  r.fail(&n, fmt::format("field '{}': a component is one of x, y, z, rx, ry, rz or 1..6", field));
}

// x stations from a to b at most h apart, containing every `must` station.
std::vector<double> stations_with(double a, double b, double h, std::vector<double> must) {
  std::vector<double> s =
      uniform_stations(a, b, std::max(1, static_cast<int>(std::ceil((b - a) / h - 1e-9))));
  std::sort(must.begin(), must.end());
  std::vector<double> out;
  for (double x : s) {
    bool near = false;
    for (double m : must) near = near || std::abs(x - m) < 0.25 * h;
    if (!near) out.push_back(x);
  }
  for (double m : must) out.push_back(m);
  std::sort(out.begin(), out.end());
  out.erase(std::unique(out.begin(), out.end(),
                        [&](double p, double q) { return std::abs(p - q) < 1e-9 * h; }),
            out.end());
  return out;
}

}  // namespace

std::vector<Eigen::Vector2d> staggered_rivets(double length, double overlap, int count,
                                              double row_offset) {
  std::vector<Eigen::Vector2d> r;
  const double start = length - overlap;
  for (int i = 0; i < count; ++i)
    r.emplace_back(start + (i + 0.5) * overlap / count, i % 2 == 0 ? row_offset : -row_offset);
  return r;
}

namespace {

// Five z sensors along strip 1's centre line, ends included.
std::vector<SensorDescription> default_sensors(double length) {
  std::vector<SensorDescription> s;
  for (int k = 0; k <= 4; ++k) s.push_back({9001 + k, 1, length * k / 4, 0.0, {3}});
  return s;
}

}  // namespace

RivetedBeamDescription default_riveted_beam() {
  RivetedBeamDescription d;
  d.rivets = staggered_rivets(d.length, d.overlap, 24, d.width / 4);
  d.sensors = default_sensors(d.length);
  return d;
}

RivetedBeamDescription read_riveted_beam_description(const std::filesystem::path& path) {
  const Reader r{path.string()};
  data::require_regular_file(path);
  toml::table doc;
  try {
    doc = toml::parse_file(path.string());
  } catch (const toml::parse_error& e) {
    if (!std::filesystem::exists(path)) r.fail(nullptr, "cannot open the description file");
    throw InputError(where(r.file, static_cast<long>(e.source().begin.line),
                           fmt::format("TOML syntax: {}", e.description())));
  }
  r.reject_unknown(
      doc, "",
      {"strips", "material", "mesh", "rivets", "joints", "joint_set", "reduction", "sensor"});
  RivetedBeamDescription d = default_riveted_beam();
  d.source = path.string();

  const toml::table* strips = r.table(doc, "strips");
  if (strips) r.reject_unknown(*strips, "strips", {"length", "width", "thickness", "overlap"});
  d.length = r.number(strips, "strips", "length").value_or(d.length);
  d.width = r.number(strips, "strips", "width").value_or(d.width);
  d.thickness = r.number(strips, "strips", "thickness").value_or(d.thickness);
  d.overlap = r.number(strips, "strips", "overlap").value_or(d.length);

  const toml::table* mat = r.table(doc, "material");
  if (mat) r.reject_unknown(*mat, "material", {"youngs_modulus", "poissons_ratio", "density"});
  d.youngs_modulus = r.number(mat, "material", "youngs_modulus").value_or(d.youngs_modulus);
  d.poissons_ratio = r.number(mat, "material", "poissons_ratio").value_or(d.poissons_ratio);
  d.density = r.number(mat, "material", "density").value_or(d.density);

  const toml::table* mesh = r.table(doc, "mesh");
  if (mesh) {
    r.reject_unknown(*mesh, "mesh", {"element", "size"});
    if (const toml::node* e = mesh->get("element")) {
      const auto s = e->value<std::string>();
      if (!e->is_string() || (*s != "shell" && *s != "beam"))
        r.fail(e, "field 'mesh.element' must be \"shell\" or \"beam\"");
      d.shell = *s == "shell";
    }
  }
  d.element_size = r.number(mesh, "mesh", "size").value_or(d.element_size);

  const toml::table* riv = r.table(doc, "rivets");
  if (riv)
    r.reject_unknown(*riv, "rivets", {"count", "row_offset", "coupling_radius", "positions"});
  d.coupling_radius = r.number(riv, "rivets", "coupling_radius").value_or(d.coupling_radius);
  const long count = r.integer(riv, "rivets", "count").value_or(24);
  const double row_offset = r.number(riv, "rivets", "row_offset").value_or(d.width / 4);
  if (count < 1 || count > 999)
    r.fail(riv ? riv->get("count") : nullptr, "field 'rivets.count' must be 1..999");
  d.rivets = staggered_rivets(d.length, d.overlap, static_cast<int>(count), row_offset);
  if (riv && riv->get("positions")) {
    const toml::node* pn = riv->get("positions");
    const toml::array* arr = pn->as_array();
    if (!arr || arr->empty())
      r.fail(pn, "field 'rivets.positions' must be a non-empty array of [x, y]");
    d.rivets.clear();
    for (const toml::node& p : *arr) {
      const toml::array* xy = p.as_array();
      if (!xy || xy->size() != 2 || !(*xy)[0].value<double>() || !(*xy)[1].value<double>())
        r.fail(&p, "field 'rivets.positions': each entry must be [x, y] in metres");
      d.rivets.emplace_back(*(*xy)[0].value<double>(), *(*xy)[1].value<double>());
    }
  }

  const toml::table* j = r.table(doc, "joints");
  if (j) r.reject_unknown(*j, "joints", {"Kt", "Fs", "chi", "beta", "kz", "rxy", "rz"});
  d.kt = r.number(j, "joints", "Kt").value_or(d.kt);
  d.fs = r.number(j, "joints", "Fs").value_or(d.fs);
  d.chi = r.number(j, "joints", "chi").value_or(d.chi);
  d.beta = r.number(j, "joints", "beta").value_or(d.beta);
  d.kz = r.number(j, "joints", "kz").value_or(d.kz);
  d.rxy = r.number(j, "joints", "rxy").value_or(d.rxy);
  d.rz = r.number(j, "joints", "rz").value_or(d.rz);

  // [[joint_set]]: some rivets with an Iwan set of their own (a bolted pair beside riveted
  // ones); its parameters default to [joints]'.
  if (const toml::node* jn = doc.get("joint_set")) {
    const toml::array* arr = jn->as_array();
    if (!arr) r.fail(jn, "'joint_set' must be an array of tables [[joint_set]]");
    int k = 0;
    for (const toml::node& item : *arr) {
      ++k;
      const toml::table* t = item.as_table();
      const std::string name = fmt::format("joint_set[{}]", k);
      if (!t) r.fail(&item, fmt::format("'{}' must be a table", name));
      r.reject_unknown(*t, name, {"name", "rivets", "Kt", "Fs", "chi", "beta"});
      JointSetDescription js;
      const toml::node* nn = t->get("name");
      if (!nn || !nn->is_string())
        r.fail(nn ? nn : &item, fmt::format("field '{}.name' is required, a word", name));
      js.name = *nn->value<std::string>();
      const toml::node* rn = t->get("rivets");
      const toml::array* ra = rn ? rn->as_array() : nullptr;
      if (!ra || ra->empty())
        r.fail(rn ? rn : &item,
               fmt::format("field '{}.rivets' is required: a non-empty array of rivet numbers "
                           "(1-based, as in dofs.csv)",
                           name));
      for (const toml::node& v : *ra) {
        const auto n = v.value<int64_t>();
        if (!v.is_integer() || !n)
          r.fail(&v, fmt::format("field '{}.rivets': each entry must be a rivet number", name));
        js.rivets.push_back(static_cast<int>(*n));
      }
      js.kt = r.number(t, name, "Kt").value_or(d.kt);
      js.fs = r.number(t, name, "Fs").value_or(d.fs);
      js.chi = r.number(t, name, "chi").value_or(d.chi);
      js.beta = r.number(t, name, "beta").value_or(d.beta);
      d.joint_sets.push_back(std::move(js));
    }
  }

  const toml::table* red = r.table(doc, "reduction");
  if (red) r.reject_unknown(*red, "reduction", {"fixed_interface_modes"});
  d.fixed_interface_modes = static_cast<int>(
      r.integer(red, "reduction", "fixed_interface_modes").value_or(d.fixed_interface_modes));

  d.sensors = default_sensors(d.length);
  if (const toml::node* sn = doc.get("sensor")) {
    const toml::array* arr = sn->as_array();
    if (!arr) r.fail(sn, "'sensor' must be an array of tables [[sensor]]");
    d.sensors.clear();
    int k = 0;
    for (const toml::node& item : *arr) {
      ++k;
      const toml::table* t = item.as_table();
      const std::string name = fmt::format("sensor[{}]", k);
      if (!t) r.fail(&item, fmt::format("'{}' must be a table", name));
      r.reject_unknown(*t, name, {"label", "strip", "x", "y", "components"});
      SensorDescription s;
      s.label = static_cast<int>(r.integer(t, name, "label").value_or(9000 + k));
      s.strip = static_cast<int>(r.integer(t, name, "strip").value_or(1));
      const auto x = r.number(t, name, "x");
      if (!x) r.fail(&item, fmt::format("field '{}.x' is required", name));
      s.x = *x;
      s.y = r.number(t, name, "y").value_or(0.0);
      if (const toml::node* c = t->get("components")) {
        const toml::array* ca = c->as_array();
        if (!ca || ca->empty())
          r.fail(c, fmt::format("field '{}.components' must be a non-empty array", name));
        for (const toml::node& cc : *ca)
          s.components.push_back(component_number(r, cc, name + ".components"));
      } else {
        s.components = {3};
      }
      d.sensors.push_back(s);
    }
  }
  validate(d);
  return d;
}

void validate(const RivetedBeamDescription& d) {
  const auto fail = [&](const std::string& m) { throw InputError(where(d.source, 0, m)); };
  const auto positive = [&](double v, const char* field) {
    if (!(v > 0) || !std::isfinite(v))
      fail(fmt::format("field '{}' must be > 0 (got {})", field, v));
  };
  positive(d.length, "strips.length");
  positive(d.width, "strips.width");
  positive(d.thickness, "strips.thickness");
  positive(d.overlap, "strips.overlap");
  if (d.overlap > d.length * (1 + 1e-12))
    fail("field 'strips.overlap' must not exceed strips.length");
  positive(d.youngs_modulus, "material.youngs_modulus");
  positive(d.density, "material.density");
  if (!(d.poissons_ratio > -1 && d.poissons_ratio < 0.5))
    fail("field 'material.poissons_ratio' must be in (-1, 0.5)");
  positive(d.element_size, "mesh.size");
  if (d.element_size > d.length / 4) fail("field 'mesh.size' must be at most strips.length / 4");
  if (d.shell && (d.length / d.element_size) * (d.width / d.element_size) > 2e6)
    fail(
        fmt::format("field 'mesh.size' = {} m is too small: {:.3g} shell elements per strip, "
                    "the limit is 2000000",
                    d.element_size, (d.length / d.element_size) * (d.width / d.element_size)));
  // The reduction holds dense columns as long as the model (6 DOFs per beam node) for every
  // interface DOF and kept mode: 1e5 elements per strip keep that below about 0.5 GB.
  if (!d.shell && d.length / d.element_size > 1e5)
    fail(
        fmt::format("field 'mesh.size' = {} m is too small: {:.3g} beam elements per strip, "
                    "the limit is 100000",
                    d.element_size, d.length / d.element_size));
  positive(d.coupling_radius, "rivets.coupling_radius");
  if (const std::string e = model::iwan_parameter_error({d.fs, d.kt, d.chi, d.beta}); !e.empty())
    fail(fmt::format("field 'joints.{}'{}", e.substr(0, e.find(' ')), e.substr(e.find(' '))));
  std::set<std::string> set_names;
  for (std::size_t k = 0; k < d.joint_sets.size(); ++k) {
    const JointSetDescription& js = d.joint_sets[k];
    const std::string field = fmt::format("joint_set[{}]", k + 1);
    const bool word = !js.name.empty() && std::all_of(js.name.begin(), js.name.end(), [](char c) {
      return std::isalnum(static_cast<unsigned char>(c)) || c == '_' || c == '-';
    });
    if (!word)
      fail(fmt::format("field '{}.name' = '{}' must be a word (letters, digits, _ or -)", field,
                       js.name));
    if (js.name == "rivet" || !set_names.insert(js.name).second)
      fail(fmt::format("field '{}.name' = '{}' is taken ({})", field, js.name,
                       js.name == "rivet" ? "iwan.rivet is [joints]' set of the other rivets"
                                          : "two [[joint_set]] share it"));
    if (const std::string e = model::iwan_parameter_error({js.fs, js.kt, js.chi, js.beta});
        !e.empty())
      fail(fmt::format("field '{}.{}'{}", field, e.substr(0, e.find(' ')), e.substr(e.find(' '))));
  }
  positive(d.kz, "joints.kz");
  positive(d.rxy, "joints.rxy");
  positive(d.rz, "joints.rz");
  if (d.fixed_interface_modes < 0) fail("field 'reduction.fixed_interface_modes' must be >= 0");
  if (d.rivets.empty()) fail("no rivets");
  if (d.rivets.size() > 999) fail("at most 999 rivets");
  const double x0 = d.length - d.overlap;
  for (std::size_t i = 0; i < d.rivets.size(); ++i) {
    const Eigen::Vector2d& p = d.rivets[i];
    if (p.x() < x0 || p.x() > d.length || std::abs(p.y()) > d.width / 2)
      fail(
          fmt::format("rivets: rivet {} at ({}, {}) lies outside the overlap x in [{}, {}], "
                      "|y| <= {}",
                      i + 1, p.x(), p.y(), x0, d.length, d.width / 2));
    for (std::size_t k = 0; k < i; ++k)
      if ((p - d.rivets[k]).norm() < 2 * d.coupling_radius && d.shell)
        fail(
            fmt::format("rivets: the coupling patches of rivets {} and {} overlap (closer "
                        "than 2 * rivets.coupling_radius)",
                        k + 1, i + 1));
      else if (!d.shell && std::abs(p.x() - d.rivets[k].x()) < 0.25 * d.element_size)
        fail(
            fmt::format("rivets: rivets {} and {} share a beam station; the beam model needs "
                        "rivets at distinct x (more than mesh.size / 4 apart)",
                        k + 1, i + 1));
  }
  std::map<int, std::string> set_of_rivet;
  for (std::size_t k = 0; k < d.joint_sets.size(); ++k) {
    for (const int r : d.joint_sets[k].rivets) {
      if (r < 1 || r > static_cast<int>(d.rivets.size()))
        fail(fmt::format("field 'joint_set[{}].rivets': rivet {} does not exist (1 to {})", k + 1,
                         r, d.rivets.size()));
      if (const auto [at, fresh] = set_of_rivet.emplace(r, d.joint_sets[k].name); !fresh)
        fail(fmt::format("field 'joint_set[{}].rivets': rivet {} is in set '{}' already", k + 1, r,
                         at->second));
    }
  }
  std::set<int> labels;
  for (std::size_t i = 0; i < d.sensors.size(); ++i) {
    const SensorDescription& s = d.sensors[i];
    const std::string name = fmt::format("sensor[{}]", i + 1);
    if (s.label <= 0 || (s.label > 1000 && s.label <= 2999 && s.label % 1000 != 0))
      fail(fmt::format("field '{}.label' must be positive and not a rivet label 1001..2999", name));
    if (!labels.insert(s.label).second)
      fail(fmt::format("field '{}.label': label {} is used twice", name, s.label));
    if (s.strip != 1 && s.strip != 2) fail(fmt::format("field '{}.strip' must be 1 or 2", name));
    const double xs = s.strip == 1 ? 0 : x0;
    if (s.x < xs - 1e-12 || s.x > xs + d.length + 1e-12 || std::abs(s.y) > d.width / 2)
      fail(fmt::format("field '{}': ({}, {}) lies outside strip {}", name, s.x, s.y, s.strip));
    if (s.components.empty()) fail(fmt::format("field '{}.components' is empty", name));
    if (!d.shell)
      for (std::size_t k = 0; k < d.rivets.size(); ++k)
        if (std::abs(s.x - d.rivets[k].x()) < 0.25 * d.element_size)
          fail(fmt::format("{} shares the beam station of rivet {}; move it (beam model)", name,
                           k + 1));
  }
}

RivetedBeam build_riveted_beam(const RivetedBeamDescription& d) {
  RivetedBeam out;
  FeModel& fe = out.fe;
  const double t = d.thickness, h = d.element_size;
  const double x_start[2] = {0.0, d.length - d.overlap};
  const double z_mid[2] = {0.0, t};
  const double z_interface = t / 2;
  const int nr = static_cast<int>(d.rivets.size());
  std::vector<std::vector<int>> ref(2, std::vector<int>(nr));
  std::vector<LabelledNode> sensors;

  for (int s = 0; s < 2; ++s) {
    std::vector<double> sensor_x;
    for (const auto& sd : d.sensors)
      if (sd.strip == s + 1) sensor_x.push_back(sd.x);
    if (d.shell) {
      const ShellSection sec{d.youngs_modulus, d.poissons_ratio, d.density, t, 1e-3};
      const int nx = std::max(1, static_cast<int>(std::ceil(d.length / h - 1e-9)));
      const int ny = std::max(2, static_cast<int>(std::ceil(d.width / h - 1e-9)));
      const StripGrid g =
          add_shell_strip(fe, uniform_stations(x_start[s], x_start[s] + d.length, nx),
                          uniform_stations(-d.width / 2, d.width / 2, ny), z_mid[s], sec);
      for (int r = 0; r < nr; ++r) {
        const Eigen::Vector3d p(d.rivets[r].x(), d.rivets[r].y(), z_mid[s]);
        ref[s][r] = fe.add_node({p.x(), p.y(), z_interface});
        const std::vector<int> patch = fe.nodes_within(p, d.coupling_radius, g.nodes);
        if (patch.size() < 3)
          throw InputError(
              where(d.source, 0,
                    fmt::format("rivet {}: only {} shell nodes of strip {} within "
                                "rivets.coupling_radius = {} m; increase it or refine mesh.size",
                                r + 1, patch.size(), s + 1, d.coupling_radius)));
        fe.add_distributing_coupling(ref[s][r], patch);
      }
      for (const auto& sd : d.sensors) {
        if (sd.strip != s + 1) continue;
        const Eigen::Vector3d p(sd.x, sd.y, z_mid[s]);
        int best = g.nodes[0];
        for (int n : g.nodes)
          if ((fe.node(n) - p).norm() < (fe.node(best) - p).norm()) best = n;
        for (const auto& other : sensors)
          if (other.node == best)
            throw InputError(where(d.source, 0,
                                   fmt::format("sensors {} and {} fall on the same mesh node",
                                               other.label, sd.label)));
        fe.keep_independent(best);
        sensors.push_back({best, sd.label, sd.components});
      }
    } else {
      const BeamSection sec =
          rectangular_section(d.youngs_modulus, d.poissons_ratio, d.density, d.width, t);
      std::vector<double> must = sensor_x;
      for (const auto& p : d.rivets) must.push_back(p.x());
      const std::vector<double> xs = stations_with(x_start[s], x_start[s] + d.length, h, must);
      const std::vector<int> line = add_beam_line(fe, xs, 0.0, z_mid[s], sec);
      const auto station = [&](double x) {
        int best = 0;
        for (int i = 0; i < static_cast<int>(xs.size()); ++i)
          if (std::abs(xs[i] - x) < std::abs(xs[best] - x)) best = i;
        return line[best];
      };
      for (int r = 0; r < nr; ++r) {
        ref[s][r] = fe.add_node({d.rivets[r].x(), d.rivets[r].y(), z_interface});
        fe.add_rigid_link(ref[s][r], station(d.rivets[r].x()));
      }
      for (const auto& sd : d.sensors)
        if (sd.strip == s + 1) sensors.push_back({station(sd.x), sd.label, sd.components});
    }
  }
  for (int s = 0; s < 2; ++s)
    for (int r = 0; r < nr; ++r)
      out.boundary.push_back({ref[s][r], 1000 * (s + 1) + r + 1, {1, 2, 3, 4, 5, 6}});
  for (const auto& sn : sensors) out.boundary.push_back(sn);
  static const char* const kElement[6] = {"iwan.rivet", "iwan.rivet", "spring.kz",
                                          "spring.rxy", "spring.rxy", "spring.rz"};
  std::vector<std::string> iwan(static_cast<std::size_t>(nr), "iwan.rivet");
  for (const JointSetDescription& js : d.joint_sets)
    for (const int r : js.rivets) iwan[static_cast<std::size_t>(r - 1)] = "iwan." + js.name;
  for (int r = 0; r < nr; ++r)
    for (int c = 1; c <= 6; ++c)
      out.joints.push_back({r + 1, ref[0][r], ref[1][r], c,
                            c <= 2 ? iwan[static_cast<std::size_t>(r)] : kElement[c - 1]});
  return out;
}

IwanParameters joint_iwan(const RivetedBeamDescription& d, const std::string& element) {
  if (element == "iwan.rivet") return {d.fs, d.kt, d.chi, d.beta};
  for (const JointSetDescription& js : d.joint_sets)
    if (element == "iwan." + js.name) return {js.fs, js.kt, js.chi, js.beta};
  throw std::invalid_argument("unknown joint element " + element);
}

double joint_stiffness(const RivetedBeamDescription& d, const std::string& element) {
  if (element.starts_with("iwan.")) return joint_iwan(d, element).Kt;
  if (element == "spring.kz") return d.kz;
  if (element == "spring.rxy") return d.rxy;
  if (element == "spring.rz") return d.rz;
  throw std::invalid_argument("unknown joint element " + element);
}

}  // namespace jointlab::model::fe
