#include "jointlab/campaign/campaign.h"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <set>
#include <sstream>

#include <fmt/format.h>
#include <fmt/ranges.h>
#include <toml++/toml.h>

#include "jointlab/core/error.h"

namespace jointlab::campaign {

bool CampaignUpdate::fits(const std::string& mode) const {
  return modes.empty() || std::find(modes.begin(), modes.end(), mode) != modes.end();
}

namespace {

namespace fs = std::filesystem;

// Whether `p` names a regular file. A name the system cannot even look up (a component longer
// than it allows) names none: the throwing std::filesystem::is_regular_file ended the program
// on such a campaign file with an uncaught filesystem_error (found by fuzz_campaign).
bool is_file(const fs::path& p) {
  std::error_code ec;
  return fs::is_regular_file(p, ec);
}

// Names the file and line of every defect.
struct Context {
  std::string file;
  fs::path dir;
  [[noreturn]] void fail(const toml::node& node, const std::string& message) const {
    throw InputError(where(file, static_cast<long>(node.source().begin.line), message));
  }
  [[noreturn]] void fail(const std::string& message) const {
    throw InputError(where(file, 0, message));
  }
  fs::path resolve(const std::string& p) const {
    const fs::path path(p);
    return (path.is_absolute() ? path : dir / path).lexically_normal();
  }
};

void reject_unknown(const Context& ctx, const toml::table& t, const std::string& name,
                    const std::set<std::string>& known) {
  for (auto&& [key, value] : t) {
    if (known.count(std::string(key.str()))) continue;
    std::string list;
    for (const std::string& k : known) list += (list.empty() ? "" : ", ") + k;
    ctx.fail(value, fmt::format("{}: unknown key '{}' (expected {})", name, key.str(), list));
  }
}

const toml::table& table(const Context& ctx, const toml::node& n, const std::string& field) {
  const toml::table* t = n.as_table();
  if (!t) ctx.fail(n, fmt::format("{} must be a table", field));
  return *t;
}

double number(const Context& ctx, const toml::node& n, const std::string& field) {
  if (!(n.is_integer() || n.is_floating_point()))
    ctx.fail(n, fmt::format("{} must be a number", field));
  const double v = *n.value<double>();
  if (!std::isfinite(v)) ctx.fail(n, fmt::format("{} must be finite", field));
  return v;
}

int integer(const Context& ctx, const toml::node& n, const std::string& field) {
  if (!n.is_integer()) ctx.fail(n, fmt::format("{} must be an integer", field));
  return static_cast<int>(*n.value<int64_t>());
}

std::string text(const Context& ctx, const toml::node& n, const std::string& field) {
  if (!n.is_string()) ctx.fail(n, fmt::format("{} must be a string", field));
  return *n.value<std::string>();
}

bool boolean(const Context& ctx, const toml::node& n, const std::string& field) {
  if (!n.is_boolean()) ctx.fail(n, fmt::format("{} must be true or false", field));
  return *n.value<bool>();
}

Quantity quantity(const Context& ctx, const toml::node& n, const std::string& field) {
  const auto q = parse_quantity(text(ctx, n, field));
  if (!q || *q == Quantity::kForce)
    ctx.fail(n,
             fmt::format("{} must be \"displacement\", \"velocity\" or \"acceleration\"", field));
  return *q;
}

const toml::array& array(const Context& ctx, const toml::node& n, const std::string& field) {
  const toml::array* a = n.as_array();
  if (!a) ctx.fail(n, fmt::format("{} must be an array", field));
  return *a;
}

// A setting of an update table: a number, a text, a flag, or a table of per-set bounds
// { "<set>" = [lower, upper], ... }; the settings' meaning is checked where they are used.
CampaignSetting setting(const Context& ctx, const toml::node& n, const std::string& field) {
  const long line = static_cast<long>(n.source().begin.line);
  if (n.is_string()) return {*n.value<std::string>(), line};
  if (const toml::table* t = n.as_table()) {
    std::vector<SetBounds> bounds;
    for (auto&& [set, v] : *t) {
      const std::string name = fmt::format("{}.\"{}\"", field, set.str());
      const toml::array* a = v.as_array();
      if (!a || a->size() != 2) ctx.fail(v, fmt::format("{} must be [lower, upper]", name));
      const double lo = number(ctx, (*a)[0], name), hi = number(ctx, (*a)[1], name);
      if (!(lo > 0 && lo < hi)) ctx.fail(v, fmt::format("{}: need 0 < lower < upper", name));
      bounds.push_back({std::string(set.str()), lo, hi});
    }
    return {std::move(bounds), line};
  }
  if (n.is_boolean()) return CampaignSetting::flag(*n.value<bool>(), line);
  if (!(n.is_integer() || n.is_floating_point()))
    ctx.fail(n, fmt::format("{} must be a number, a string, true or false, or a table of bounds",
                            field));
  return {number(ctx, n, field), line};
}

CampaignUpdate read_update(const Context& ctx, const toml::node& n, const std::string& field) {
  CampaignUpdate u;
  u.enabled = true;
  for (auto&& [key, value] : table(ctx, n, field)) {
    const std::string k(key.str());
    if (k == "enabled") {
      u.enabled = boolean(ctx, value, field + ".enabled");
    } else if (k == "sets") {
      for (const toml::node& s : array(ctx, value, field + ".sets"))
        u.sets.push_back(text(ctx, s, field + ".sets"));
      // run identifies one Iwan set; a second one named was left out without a word (a beam
      // with bolts and rivets, sets = ["iwan.bolt", "iwan.rivet"], fitted the bolts alone to
      // both modes, the rivets' mode included).
      if (field == "update.iwan" && u.sets.size() > 1) {
        ctx.fail(value,
                 fmt::format("update.iwan.sets names {} Iwan sets ({}), but run identifies one: "
                             "name the one to identify and, in update.iwan modes, the [[mode]]s "
                             "whose joint dissipation it carries; identify another set in a run "
                             "of its own or with update-iwan --set",
                             u.sets.size(), fmt::join(u.sets, ", ")));
      }
    } else if (k == "modes") {
      for (const toml::node& s : array(ctx, value, field + ".modes"))
        u.modes.push_back(text(ctx, s, field + ".modes"));
    } else {
      u.settings[k] = setting(ctx, value, field + "." + k);
    }
  }
  return u;
}

}  // namespace

int Campaign::hit_count() const {
  int n = 0;
  for (const CampaignGroup& g : groups) n += static_cast<int>(g.files.size());
  return n;
}

const CampaignChannel* Campaign::channel(const std::string& name) const {
  for (const CampaignChannel& c : channels)
    if (c.name == name) return &c;
  return nullptr;
}

namespace {

// [campaign]: name, quantities and the truth file.
void read_campaign_table(const Context& ctx, const toml::table& doc, Campaign& c) {
  if (const toml::node* n = doc.get("campaign")) {
    const toml::table& t = table(ctx, *n, "[campaign]");
    reject_unknown(ctx, t, "[campaign]", {"name", "quantity", "amplitude", "truth"});
    if (const toml::node* v = t.get("name")) c.name = text(ctx, *v, "campaign.name");
    if (const toml::node* v = t.get("quantity"))
      c.quantity = quantity(ctx, *v, "campaign.quantity");
    if (const toml::node* v = t.get("amplitude"))
      c.amplitude = quantity(ctx, *v, "campaign.amplitude");
    if (const toml::node* v = t.get("truth")) {
      c.truth = ctx.resolve(text(ctx, *v, "campaign.truth"));
      if (!is_file(c.truth))
        ctx.fail(*v, fmt::format("campaign.truth: no file {}", c.truth.string()));
    }
  }
}

// [model]: a model file or a description to build.
void read_model_table(const Context& ctx, const toml::table& doc, Campaign& c) {
  if (const toml::node* n = doc.get("model")) {
    const toml::table& t = table(ctx, *n, "[model]");
    reject_unknown(ctx, t, "[model]", {"file", "description", "fixed_interface_modes"});
    const toml::node* f = t.get("file");
    const toml::node* d = t.get("description");
    if ((f != nullptr) == (d != nullptr))
      ctx.fail(*n,
               "[model]: give exactly one of 'file' (a model.toml) or 'description' "
               "(a riveted-beam description for build-model)");
    const fs::path p = ctx.resolve(text(ctx, f ? *f : *d, f ? "model.file" : "model.description"));
    if (!is_file(p)) ctx.fail(f ? *f : *d, fmt::format("model: no file {}", p.string()));
    (f ? c.model.file : c.model.description) = p;
    if (const toml::node* v = t.get("fixed_interface_modes")) {
      if (!d) ctx.fail(*v, "model.fixed_interface_modes applies only with model.description");
      c.model.fixed_interface_modes = integer(ctx, *v, "model.fixed_interface_modes");
      if (c.model.fixed_interface_modes < 0)
        ctx.fail(*v, "model.fixed_interface_modes must be >= 0");
    }
  }
}

// [[group]]: the hits, with unique group names and file stems.
void read_groups(const Context& ctx, const toml::table& doc, Campaign& c) {
  const toml::node* groups = doc.get("group");
  if (!groups) ctx.fail("no [[group]] of test files");
  std::set<std::string> group_names, stems;
  for (const toml::node& item : array(ctx, *groups, "[[group]]")) {
    const toml::table& t = table(ctx, item, "[[group]]");
    reject_unknown(ctx, t, "[[group]]", {"name", "level", "files"});
    CampaignGroup g;
    const toml::node* name = t.get("name");
    if (!name) ctx.fail(item, "[[group]]: missing 'name'");
    g.name = text(ctx, *name, "group.name");
    if (g.name.empty() || g.name.find_first_of("/\\ ") != std::string::npos)
      ctx.fail(*name, "group.name must be a non-empty word without spaces or slashes");
    if (!group_names.insert(g.name).second)
      ctx.fail(*name, fmt::format("group.name '{}' appears twice", g.name));
    g.level = g.name;
    if (const toml::node* v = t.get("level")) g.level = text(ctx, *v, "group.level");
    const toml::node* files = t.get("files");
    if (!files) ctx.fail(item, fmt::format("group '{}': missing 'files'", g.name));
    for (const toml::node& f : array(ctx, *files, "group.files")) {
      const fs::path p = ctx.resolve(text(ctx, f, "group.files"));
      if (!is_file(p)) ctx.fail(f, fmt::format("group '{}': no test file {}", g.name, p.string()));
      if (!stems.insert(p.stem().string()).second)
        ctx.fail(f, fmt::format("group '{}': a second test file named '{}' (file names identify "
                                "hits and must differ)",
                                g.name, p.stem().string()));
      g.files.push_back(p);
    }
    if (g.files.empty()) ctx.fail(*files, fmt::format("group '{}': no files", g.name));
    c.groups.push_back(std::move(g));
  }
}

// [[channel]]: names, DOFs and signs.
void read_channels(const Context& ctx, const toml::table& doc, Campaign& c) {
  const toml::node* channels = doc.get("channel");
  if (!channels) ctx.fail("no [[channel]]");
  for (const toml::node& item : array(ctx, *channels, "[[channel]]")) {
    const toml::table& t = table(ctx, item, "[[channel]]");
    reject_unknown(ctx, t, "[[channel]]", {"name", "dof", "sign"});
    CampaignChannel ch;
    const toml::node* name = t.get("name");
    if (!name) ctx.fail(item, "[[channel]]: missing 'name'");
    ch.name = text(ctx, *name, "channel.name");
    if (c.channel(ch.name)) ctx.fail(*name, fmt::format("channel '{}' appears twice", ch.name));
    if (const toml::node* v = t.get("dof")) {
      if (v->is_integer()) {
        ch.dof = std::to_string(*v->value<int64_t>());
      } else {
        ch.dof = text(ctx, *v, "channel.dof");
      }
    }
    if (const toml::node* v = t.get("sign")) {
      ch.sign = number(ctx, *v, "channel.sign");
      if (ch.sign != 1.0 && ch.sign != -1.0) ctx.fail(*v, "channel.sign must be 1 or -1");
    }
    c.channels.push_back(ch);
  }
}

// [[mode]]: names (unique), bands, model modes and reference channels.
void read_modes(const Context& ctx, const toml::table& doc, Campaign& c) {
  const toml::node* modes = doc.get("mode");
  if (!modes) ctx.fail("no [[mode]]");
  for (const toml::node& item : array(ctx, *modes, "[[mode]]")) {
    const toml::table& t = table(ctx, item, "[[mode]]");
    reject_unknown(ctx, t, "[[mode]]",
                   {"name", "band", "model_mode", "reference", "stepped_sine", "backbones"});
    CampaignMode m;
    m.name = fmt::format("mode {}", c.modes.size() + 1);
    if (const toml::node* v = t.get("name")) {
      m.name = text(ctx, *v, "mode.name");
      for (const CampaignMode& other : c.modes)
        if (other.name == m.name)
          ctx.fail(*v, fmt::format("mode.name: '{}' names two [[mode]] tables", m.name));
    }
    const toml::node* band = t.get("band");
    if (!band) ctx.fail(item, fmt::format("{}: missing 'band = [LO, HI]' (Hz)", m.name));
    const toml::array& b = array(ctx, *band, "mode.band");
    if (b.size() != 2) ctx.fail(*band, "mode.band must be [LO, HI] in Hz");
    m.band = {number(ctx, *b.get(0), "mode.band"), number(ctx, *b.get(1), "mode.band")};
    if (!(m.band.lo > 0 && m.band.hi > m.band.lo))
      ctx.fail(*band, "mode.band: need 0 < LO < HI (Hz)");
    if (const toml::node* v = t.get("model_mode")) {
      m.model_mode = integer(ctx, *v, "mode.model_mode");
      if (m.model_mode < 1) ctx.fail(*v, "mode.model_mode must be >= 1 (elastic modes from 1)");
    }
    m.reference = c.channels.front().name;
    if (const toml::node* v = t.get("reference")) {
      m.reference = text(ctx, *v, "mode.reference");
      if (!c.channel(m.reference))
        ctx.fail(*v, fmt::format("mode.reference: '{}' is not a [[channel]]", m.reference));
    }
    if (const toml::node* v = t.get("stepped_sine")) {
      for (const toml::node& f : array(ctx, *v, "mode.stepped_sine")) {
        const fs::path p = ctx.resolve(text(ctx, f, "mode.stepped_sine"));
        if (!is_file(p)) ctx.fail(f, fmt::format("mode.stepped_sine: no file {}", p.string()));
        m.stepped_sine.push_back(p);
      }
    }
    if (const toml::node* v = t.get("backbones")) {
      for (const toml::node& f : array(ctx, *v, "mode.backbones")) {
        const fs::path p = ctx.resolve(text(ctx, f, "mode.backbones"));
        if (!is_file(p)) ctx.fail(f, fmt::format("mode.backbones: no file {}", p.string()));
        m.backbones.push_back(p);
      }
    }
    c.modes.push_back(m);
  }
  if (c.modes.empty()) ctx.fail(*modes, "no [[mode]]");
}

// [scatter], [qsma] and [update].
void read_settings(const Context& ctx, const toml::table& doc, Campaign& c) {
  if (const toml::node* n = doc.get("scatter")) {
    const toml::table& t = table(ctx, *n, "[scatter]");
    reject_unknown(ctx, t, "[scatter]",
                   {"bins_per_decade", "confidence", "min_curves", "outlier_threshold",
                    "frequency_floor", "damping_floor", "exclude_outliers"});
    ScatterOptions& s = c.scatter;
    if (const toml::node* v = t.get("bins_per_decade"))
      s.bins_per_decade = integer(ctx, *v, "scatter.bins_per_decade");
    if (const toml::node* v = t.get("confidence"))
      s.confidence = number(ctx, *v, "scatter.confidence");
    if (const toml::node* v = t.get("min_curves"))
      s.min_curves = integer(ctx, *v, "scatter.min_curves");
    if (const toml::node* v = t.get("outlier_threshold"))
      s.outlier_threshold = number(ctx, *v, "scatter.outlier_threshold");
    if (const toml::node* v = t.get("frequency_floor"))
      s.frequency_floor = number(ctx, *v, "scatter.frequency_floor");
    if (const toml::node* v = t.get("damping_floor"))
      s.damping_floor = number(ctx, *v, "scatter.damping_floor");
    if (const toml::node* v = t.get("exclude_outliers"))
      s.exclude_outliers = boolean(ctx, *v, "scatter.exclude_outliers");
    if (const std::string why = s.check(); !why.empty()) ctx.fail(*n, "scatter." + why);
  }
  if (const toml::node* n = doc.get("qsma")) {
    const toml::table& t = table(ctx, *n, "[qsma]");
    reject_unknown(ctx, t, "[qsma]", {"points"});
    if (const toml::node* v = t.get("points")) {
      c.qsma_points = integer(ctx, *v, "qsma.points");
      if (c.qsma_points < 2 || c.qsma_points > 10000) ctx.fail(*v, "qsma.points: need 2 to 10000");
    }
  }
  if (const toml::node* n = doc.get("update")) {
    const toml::table& t = table(ctx, *n, "[update]");
    reject_unknown(ctx, t, "[update]", {"linear", "iwan"});
    if (const toml::node* v = t.get("linear"))
      c.linear_update = read_update(ctx, *v, "update.linear");
    if (const toml::node* v = t.get("iwan")) c.iwan_update = read_update(ctx, *v, "update.iwan");
  }
}

// What one table says about another: update modes, a model for updates, DOFs.
void check_cross_references(const Context& ctx, const toml::table&, const Campaign& c) {
  for (const CampaignUpdate* u : {&c.linear_update, &c.iwan_update}) {
    for (const std::string& name : u->modes) {
      const bool known = std::any_of(c.modes.begin(), c.modes.end(),
                                     [&](const CampaignMode& m) { return m.name == name; });
      if (!known)
        ctx.fail(fmt::format("{}.modes: '{}' is not the name of a [[mode]]",
                             u == &c.linear_update ? "update.linear" : "update.iwan", name));
    }
  }
  const bool has_model = !c.model.file.empty() || !c.model.description.empty();
  if (!has_model && (c.linear_update.enabled || c.iwan_update.enabled))
    ctx.fail("[update] needs a [model]");
  if (has_model) {
    for (const CampaignChannel& ch : c.channels)
      if (ch.dof.empty())
        ctx.fail(fmt::format("channel '{}': 'dof' is needed with a [model]", ch.name));
  }
}

}  // namespace

Campaign parse_campaign(const std::string& content, const fs::path& path) {
  Context ctx{path.string(), fs::absolute(path).parent_path()};
  toml::table doc;
  try {
    doc = toml::parse(content, path.string());
  } catch (const toml::parse_error& e) {
    throw InputError(where(path.string(), static_cast<long>(e.source().begin.line),
                           std::string(e.description())));
  }
  reject_unknown(ctx, doc, "campaign file",
                 {"campaign", "model", "group", "channel", "mode", "scatter", "qsma", "update"});
  Campaign c;
  c.file = fs::absolute(path).lexically_normal();
  c.name = path.stem().string();

  read_campaign_table(ctx, doc, c);
  read_model_table(ctx, doc, c);
  read_groups(ctx, doc, c);
  read_channels(ctx, doc, c);
  read_modes(ctx, doc, c);
  read_settings(ctx, doc, c);
  check_cross_references(ctx, doc, c);
  return c;
}

Campaign read_campaign(const fs::path& path) {
  std::ifstream in(path);
  if (!in) throw InputError(where(path.string(), 0, "cannot open the campaign file"));
  std::stringstream ss;
  ss << in.rdbuf();
  return parse_campaign(ss.str(), path);
}

}  // namespace jointlab::campaign
