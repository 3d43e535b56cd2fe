#include "simulation/ensemble.hpp"

#include <algorithm>
#include <atomic>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <memory>
#include <mutex>
#include <numbers>
#include <random>
#include <sstream>
#include <thread>

#include <nlohmann/json.hpp>

#include "core/errors.hpp"
#include "models/robot/strict_toml.hpp"
#include "simulation/run_documents.hpp"

namespace pumasim {
namespace {

using Kind = EnsembleFactor::Kind;

std::string full_precision(double x) {
  char buf[40];
  std::snprintf(buf, sizeof buf, "%.17g", x);
  return buf;
}

// SplitMix64's finaliser (Steele, Lea and Flood, "Fast splittable
// pseudorandom number generators", OOPSLA 2014): a bijective mix of 64 bits,
// so that neighbouring (seed, k) give unrelated generator seeds.
std::uint64_t mix64(std::uint64_t z) {
  z += 0x9e3779b97f4a7c15ULL;
  z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
  z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
  return z ^ (z >> 31);
}

// A double in [0, 1) from the generator's top 53 bits.
double unit(std::mt19937_64& g) { return static_cast<double>(g() >> 11) * 0x1.0p-53; }

// The factor's value; for a normal one, also its standard normal in z.
double draw(const EnsembleFactor& f, std::mt19937_64& g, double& z) {
  switch (f.kind) {
    case Kind::kNormal: {
      // Box-Muller (1958): two uniforms, 1 - u in (0, 1] keeps the log finite.
      const double u1 = 1.0 - unit(g), u2 = unit(g);
      const double r = std::sqrt(-2.0 * std::log(u1)), c = std::cos(2 * std::numbers::pi * u2);
      z = r * c;
      return f.a + f.b * r * c;
    }
    case Kind::kUniform:
      return f.a + (f.b - f.a) * unit(g);
    case Kind::kLogUniform:
      return std::exp(std::log(f.a) + (std::log(f.b) - std::log(f.a)) * unit(g));
    case Kind::kChoice:
      return unit(g);  // an index below
  }
  return 0;
}

std::vector<std::string> string_array(StrictTable& t, std::string_view key, bool required) {
  const toml::node* node = t.node(key);
  if (!node) {
    if (required) t.fail(key, "an array of strings", "nothing");
    return {};
  }
  const toml::array* arr = node->as_array();
  if (!arr) t.fail(key, "an array of strings", "not an array");
  std::vector<std::string> out;
  for (const toml::node& e : *arr) {
    const auto s = e.value<std::string>();
    if (!s) t.fail(key, "an array of strings", "an element that is not a string");
    out.push_back(*s);
  }
  return out;
}

EnsembleFactor read_factor(StrictTable& t) {
  EnsembleFactor f;
  f.key = t.string("key");
  if (f.key.find('.') == std::string::npos || f.key.find('=') != std::string::npos) {
    t.fail("key", "a scene key 'section.key' (pumasim keys lists them)", "'" + f.key + "'");
  }
  const std::string kind = t.string("distribution", {"normal", "uniform", "log-uniform", "choice"});
  if (kind == "normal") {
    f.kind = Kind::kNormal;
    f.a = t.number("mean");
    f.b = t.number("sd", Bounds::positive());
  } else if (kind == "choice") {
    f.kind = Kind::kChoice;
    // Each value as TOML text, as `--set` takes it.
    const toml::node* node = t.node("values");
    const toml::array* arr = node ? node->as_array() : nullptr;
    if (!arr || arr->empty())
      t.fail("values", "a non-empty array of the key's values", arr ? "an empty array" : "none");
    for (const toml::node& e : *arr) {
      if (const auto d = StrictTable::as_double(e)) {
        f.choices.push_back(full_precision(*d));
      } else if (const auto s = e.value<std::string>()) {
        f.choices.push_back(toml_string(*s));
      } else if (const auto b = e.value<bool>()) {
        f.choices.push_back(*b ? "true" : "false");
      } else {
        t.fail("values", "numbers, strings or booleans", "another kind of value");
      }
    }
  } else {
    f.kind = kind == "uniform" ? Kind::kUniform : Kind::kLogUniform;
    f.a = t.number("low", f.kind == Kind::kLogUniform ? Bounds::positive() : Bounds::any());
    f.b = t.number("high", Bounds{f.a, std::numeric_limits<double>::infinity(), true});
  }
  return f;
}

// correlate_with and correlation: factor i's partner among the earlier ones.
void read_pair(StrictTable& t, std::vector<EnsembleFactor>& factors, std::size_t i) {
  EnsembleFactor& f = factors[i];
  if (!t.has("correlate_with")) {
    if (t.has("correlation")) t.fail("correlation", "correlate_with beside it (the factor it pairs with)", "none");
    return;
  }
  const std::string with = t.string("correlate_with");
  if (f.kind != Kind::kNormal)
    t.fail("correlate_with", "a normal factor (pairs are of normals)", factor_kind_name(f.kind));
  for (std::size_t k = 0; k < i; ++k) {
    if (factors[k].key == with) f.partner = static_cast<int>(k);
  }
  if (f.partner < 0) t.fail("correlate_with", "the key of an earlier [[vary]] factor", "\"" + with + "\"");
  const EnsembleFactor& p = factors[static_cast<std::size_t>(f.partner)];
  if (p.kind != Kind::kNormal)
    t.fail("correlate_with", "a normal factor (pairs are of normals)", factor_kind_name(p.kind));
  bool paired = p.partner >= 0;
  for (std::size_t k = 0; k < i; ++k) paired = paired || factors[k].partner == f.partner;
  if (paired)
    t.fail("correlate_with", "a factor in no other pair (correlated pairs only)", "\"" + with + "\", already paired");
  f.rho = t.number("correlation", Bounds{-1, 1});
}

}  // namespace

const char* factor_kind_name(Kind kind) {
  switch (kind) {
    case Kind::kNormal:
      return "normal";
    case Kind::kUniform:
      return "uniform";
    case Kind::kLogUniform:
      return "log-uniform";
    case Kind::kChoice:
      return "choice";
  }
  return "?";
}

std::vector<std::string> EnsembleSample::sets() const {
  std::vector<std::string> out;
  for (std::size_t i = 0; i < keys.size(); ++i) out.push_back(keys[i] + "=" + values[i]);
  return out;
}

EnsembleSpec read_ensemble_file(const std::string& path) {
  const toml::table doc = parse_toml_file(path);
  StrictTable top(doc, path, "");
  EnsembleSpec s;
  s.file = path;
  const std::filesystem::path scene = top.string("scene");
  s.scene = scene.is_absolute() ? scene.string() : (std::filesystem::path(path).parent_path() / scene).string();
  s.sets = string_array(top, "set", false);
  s.samples = static_cast<long>(top.number("samples", Bounds{1, 1e7}));
  if (static_cast<double>(s.samples) != top.number("samples")) top.fail("samples", "a whole number", "a fraction");
  const double seed = top.number_or("seed", 0, Bounds{0, 9007199254740992.0});
  s.seed = static_cast<std::uint64_t>(seed);
  s.final_state = top.boolean_or("final_state", false);
  if (std::optional<StrictTable> run = top.optional_table("run")) {
    RunOptions& o = s.options;
    if (run->has("integrator")) o.integrator = run->string("integrator");
    if (run->has("backend")) o.backend = run->string("backend");
    if (run->has("dt")) o.dt = run->number("dt", Bounds::positive());
    if (run->has("rtol")) o.rtol = run->number("rtol", Bounds{0, 1, true, true});
    if (run->has("atol")) o.atol = run->number("atol", Bounds::positive());
    if (run->has("t_end")) o.t_end = run->number("t_end", Bounds::positive());
    if (run->has("max_steps")) o.max_steps = run->number("max_steps", Bounds::non_negative());
    if (run->has("max_wall")) o.max_wall = run->number("max_wall", Bounds::non_negative());
    run->finish();
  }
  if (top.has("vary")) {
    for (StrictTable& f : top.array_of_tables("vary")) {
      s.factors.push_back(read_factor(f));
      read_pair(f, s.factors, s.factors.size() - 1);
      f.finish();
    }
  }
  top.finish();
  return s;
}

EnsembleSample draw_sample(const EnsembleSpec& spec, long k) {
  EnsembleSample s;
  s.index = k;
  s.seed = mix64(mix64(spec.seed) ^ static_cast<std::uint64_t>(k));
  std::mt19937_64 g(s.seed);
  std::vector<double> z(spec.factors.size(), 0.0);  // each normal factor's standard normal
  for (std::size_t i = 0; i < spec.factors.size(); ++i) {
    const EnsembleFactor& f = spec.factors[i];
    s.keys.push_back(f.key);
    double v = draw(f, g, z[i]);
    if (f.partner >= 0) {  // the pair's: rho z_p + sqrt(1 - rho^2) z
      z[i] = f.rho * z[static_cast<std::size_t>(f.partner)] + std::sqrt(1 - f.rho * f.rho) * z[i];
      v = f.a + f.b * z[i];
    }
    if (f.kind == Kind::kChoice) {
      const auto n = f.choices.size();
      s.values.push_back(f.choices[std::min(n - 1, static_cast<std::size_t>(v * static_cast<double>(n)))]);
    } else {
      s.values.push_back(full_precision(v));
    }
  }
  return s;
}

namespace {

// The fields of one CSV line (RFC 4180 quoting; no line breaks in a field).
std::vector<std::string> csv_fields(const std::string& line, const std::string& where) {
  std::vector<std::string> out(1);
  bool quoted = false;
  for (std::size_t i = 0; i < line.size(); ++i) {
    const char c = line[i];
    if (quoted) {
      if (c == '"' && i + 1 < line.size() && line[i + 1] == '"') {
        out.back() += '"', ++i;
      } else if (c == '"') {
        quoted = false;
      } else {
        out.back() += c;
      }
    } else if (c == '"') {
      quoted = true;
    } else if (c == ',') {
      out.emplace_back();
    } else if (c != '\r') {
      out.back() += c;
    }
  }
  if (quoted) throw ConfigError(where + ": a quoted field is not closed; expected a CSV line (RFC 4180)");
  return out;
}

}  // namespace

std::vector<EnsembleSample> read_sample_table(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw ConfigError(path + ": cannot read the sample table");
  std::string line;
  if (!std::getline(in, line)) throw ConfigError(path + ":1: empty; expected a header of scene keys");
  const std::vector<std::string> keys = csv_fields(line, path + ":1");
  for (const std::string& k : keys) {
    if (k.find('.') == std::string::npos || k.find('=') != std::string::npos) {
      throw ConfigError(path + ":1: header '" + k + "': expected a scene key 'section.key' (pumasim keys lists them)");
    }
  }
  std::vector<EnsembleSample> out;
  for (long row = 2; std::getline(in, line); ++row) {
    if (line.empty() || line == "\r") continue;
    const std::string where = path + ":" + std::to_string(row);
    std::vector<std::string> values = csv_fields(line, where);
    if (values.size() != keys.size()) {
      throw ConfigError(where + ": " + std::to_string(values.size()) + " fields; expected " +
                        std::to_string(keys.size()) + ", one per key of the header");
    }
    for (std::size_t i = 0; i < values.size(); ++i) {
      if (values[i].empty()) throw ConfigError(where + ": " + keys[i] + ": empty; expected a value (TOML text)");
    }
    EnsembleSample s;
    s.index = static_cast<long>(out.size());
    s.keys = keys;
    s.values = std::move(values);
    out.push_back(std::move(s));
  }
  if (out.empty()) throw ConfigError(path + ": no rows; expected a sample per row after the header");
  return out;
}

std::vector<EnsembleSample> draw_samples(const EnsembleSpec& spec) {
  std::vector<EnsembleSample> out;
  out.reserve(static_cast<std::size_t>(spec.samples));
  for (long k = 0; k < spec.samples; ++k) out.push_back(draw_sample(spec, k));
  return out;
}

namespace {

// The samples' scene, read once (nullptr: the reader refused it or the
// common overrides, `why`).
struct EnsembleScene {
  std::unique_ptr<SceneTemplate> scene;
  std::string why;
};

EnsembleScene ensemble_scene(const EnsembleSpec& spec) {
  EnsembleScene s;
  try {
    s.scene = std::make_unique<SceneTemplate>(spec.scene, spec.sets);
  } catch (const std::exception& e) {
    s.why = e.what();
  }
  return s;
}

SampleResult run_sample(const EnsembleSpec& spec, const EnsembleScene& scene, const EnsembleSample& sample) {
  SampleResult r;
  r.sample = sample;
  RunRequest req;
  req.options = spec.options;
  req.stats = false;  // the row holds the figures
  try {
    if (!scene.scene) throw ConfigError(scene.why);
    const Scene sc = load_checked_scene(*scene.scene, sample.sets());  // load_scene(file, sets + the sample's)
    req.scene = &sc;
    const RunRecord rec = run(req);
    const RunResult& res = rec.run.result;
    r.ok = res.ok;
    r.failure_kind = res.failure_kind;
    r.failure = res.failure;
    r.t_final = res.t_final;
    r.stats = rec.run.stats;
    r.figures = rec.run.figures;
    r.state_names = rec.run.state_names;
    r.wall_time = res.wall_time;
  } catch (const std::exception& e) {  // the scene reader or the plan refused the sample's values
    r.ok = false;
    r.failure_kind = "input";
    r.failure = e.what();
  }
  return r;
}

}  // namespace

std::vector<SampleResult> run_ensemble(const EnsembleSpec& spec, const std::vector<EnsembleSample>& samples,
                                       int threads, const EnsembleProgress& progress, const bool* cancel) {
  if (threads < 1) throw std::invalid_argument("run_ensemble: expected threads >= 1, got " + std::to_string(threads));
  const long total = static_cast<long>(samples.size());
  std::vector<SampleResult> results(samples.size());
  std::atomic<long> next{0}, done{0}, failed{0};
  std::mutex report;
  const EnsembleScene scene = ensemble_scene(spec);
  const auto work = [&] {
    for (long k = next++; k < total; k = next++) {
      const auto i = static_cast<std::size_t>(k);
      if (cancel && *cancel) {
        results[i].sample = samples[i];
        results[i].failure_kind = "interrupted";
        results[i].failure = "not run: the ensemble was interrupted";
      } else {
        results[i] = run_sample(spec, scene, samples[i]);
      }
      if (!results[i].ok) ++failed;
      const long d = ++done;
      if (progress) {
        const std::lock_guard<std::mutex> lock(report);
        progress(d, failed.load(), total);
      }
    }
  };
  const int n = static_cast<int>(std::min<long>(threads, std::max<long>(total, 1)));
  std::vector<std::thread> pool;
  pool.reserve(static_cast<std::size_t>(n - 1));
  for (int t = 1; t < n; ++t) pool.emplace_back(work);
  work();  // this thread is one of the n
  for (std::thread& t : pool) t.join();
  return results;
}

namespace {

// An RFC 4180 field: quoted when it holds a comma, a quote or a line break.
std::string csv_field(const std::string& s) {
  if (s.find_first_of(",\"\r\n") == std::string::npos) return s;
  std::string out = "\"";
  for (const char c : s) out += c == '"' ? std::string("\"\"") : std::string(1, c);
  return out + "\"";
}

struct Column {
  const char* name;
  const char* unit;
  const char* meaning;
};

// The columns after sample, seed and the factors' keys, in order.
constexpr Column kColumns[] = {
    {"ok", "", "1 if the run reached its end, else 0"},
    {"failure_kind", "",
     "budget, unstable, integrator, interrupted or input (the scene refused the values); empty if ok"},
    {"t_final", "s", "where the run ended"},
    {"steps", "", "accepted steps"},
    {"rhs_evaluations", "", "right-hand sides evaluated"},
    {"jacobian_evaluations", "", "Jacobians evaluated"},
    {"rejected_steps", "", "steps rejected by the error test"},
    {"wall_time", "s", "the integration's own wall-clock time (not bitwise reproducible)"},
    {"max_path_error", "m", "the flange's largest distance to the reference point (0 without a Cartesian reference)"},
    {"rms_path_error", "m", "its root mean square over the outputs"},
    {"max_path_deviation", "m", "the flange's largest distance to the geometric path, whatever the timing"},
    {"rms_path_deviation", "m", "its root mean square over the outputs"},
    {"failure", "", "the reason, when not ok"},
};

}  // namespace

// The state names of the first result that has them (every run of one
// scene has the same layout).
static std::vector<std::string> final_state_names(const std::vector<SampleResult>& results) {
  for (const SampleResult& r : results) {
    if (!r.state_names.empty()) return r.state_names;
  }
  return {};
}

std::string ensemble_csv(const std::vector<SampleResult>& results, bool final_state) {
  std::string out = "sample,seed";
  const std::vector<std::string> no_keys;
  const std::vector<std::string>& keys = results.empty() ? no_keys : results.front().sample.keys;
  for (const std::string& k : keys) out += "," + csv_field(k);
  for (const Column& c : kColumns) out += std::string(",") + c.name;
  const std::vector<std::string> names = final_state ? final_state_names(results) : std::vector<std::string>{};
  for (const std::string& n : names) out += ",final." + csv_field(n);
  out += "\n";
  for (const SampleResult& r : results) {
    out += std::to_string(r.sample.index) + "," + std::to_string(r.sample.seed);
    for (const std::string& v : r.sample.values) out.append(",").append(csv_field(v));
    const IntegratorStats& st = r.stats;
    const RunFigures& f = r.figures;
    out += std::string(",") + (r.ok ? "1" : "0") + "," + csv_field(r.failure_kind) + "," + full_precision(r.t_final) +
           "," + std::to_string(st.steps) + "," + std::to_string(st.rhs_evaluations) + "," +
           std::to_string(st.jacobian_evaluations) + "," + std::to_string(st.rejected_steps) + "," +
           full_precision(r.wall_time) + "," + full_precision(f.max_path_error) + "," +
           full_precision(f.rms_path_error) + "," + full_precision(f.max_path_deviation) + "," +
           full_precision(f.rms_path_deviation) + "," + csv_field(r.failure);
    const bool has = r.ok && f.final_state.size() == names.size();
    for (std::size_t i = 0; i < names.size(); ++i)
      out.append(",").append(has ? full_precision(f.final_state[i]) : std::string());
    out += "\n";
  }
  return out;
}

std::string ensemble_sidecar(const EnsembleSpec& spec, const std::vector<SampleResult>& results, int threads,
                             double wall_time, const EnsembleProvenance& provenance) {
  using Json = nlohmann::ordered_json;
  Json j;
  j["written_by"] = "pumasim ensemble";
  j["build"] = version_text();
  j["ensemble_file"] = spec.file;
  j["scene"] = spec.scene;
  j["set"] = spec.sets;
  if (!spec.table.empty()) j["table"] = spec.table;
  Json run = Json::object();
  const RunOptions& o = spec.options;
  if (o.integrator) run["integrator"] = *o.integrator;
  if (o.backend) run["backend"] = *o.backend;
  if (o.dt) run["dt"] = *o.dt;
  if (o.rtol) run["rtol"] = *o.rtol;
  if (o.atol) run["atol"] = *o.atol;
  if (o.t_end) run["t_end"] = *o.t_end;
  if (o.max_steps) run["max_steps"] = *o.max_steps;
  if (o.max_wall) run["max_wall"] = *o.max_wall;
  j["run"] = run;
  j["seed"] = spec.seed;
  j["samples"] = results.size();
  j["samples_total"] = provenance.samples_total > 0 ? provenance.samples_total : static_cast<long>(results.size());
  if (provenance.shard) j["shard"] = provenance.shard->text();
  Json inputs = Json::array();
  for (const InputFile& f : provenance.inputs) {
    inputs.push_back({{"path", f.path}, {"bytes", f.bytes}, {"fnv1a64", hex64(f.fnv1a64)}});
  }
  j["inputs"] = inputs;
  Json factors = Json::array();
  for (const EnsembleFactor& f : spec.factors) {
    Json e{{"key", f.key}, {"distribution", factor_kind_name(f.kind)}};
    if (f.kind == Kind::kNormal) e["mean"] = f.a, e["sd"] = f.b;
    if (f.partner >= 0)
      e["correlate_with"] = spec.factors[static_cast<std::size_t>(f.partner)].key, e["correlation"] = f.rho;
    if (f.kind == Kind::kUniform || f.kind == Kind::kLogUniform) e["low"] = f.a, e["high"] = f.b;
    if (f.kind == Kind::kChoice) e["values"] = f.choices;
    factors.push_back(e);
  }
  j["factors"] = factors;
  Json columns = Json::array();
  columns.push_back({{"name", "sample"}, {"unit", ""}, {"meaning", "the sample's index"}});
  columns.push_back({{"name", "seed"}, {"unit", ""}, {"meaning", "its generator's seed (0: a given sample)"}});
  for (const std::string& k : results.empty() ? std::vector<std::string>{} : results.front().sample.keys) {
    std::string meaning = "the scene key's value (TOML text)";
    for (const EnsembleFactor& f : spec.factors) {
      if (f.key == k) meaning += std::string(", drawn: ") + factor_kind_name(f.kind);
    }
    if (!spec.table.empty()) meaning += ", from the table " + spec.table;
    columns.push_back({{"name", k}, {"unit", ""}, {"meaning", meaning}});
  }
  for (const Column& c : kColumns) columns.push_back({{"name", c.name}, {"unit", c.unit}, {"meaning", c.meaning}});
  if (spec.final_state) {
    for (const std::string& n : final_state_names(results)) {
      columns.push_back({{"name", "final." + n}, {"unit", ""}, {"meaning", "the state " + n + " at the last output"}});
    }
  }
  j["columns"] = columns;
  j["final_state"] = spec.final_state;
  long failed = 0;
  for (const SampleResult& r : results) failed += r.ok ? 0 : 1;
  j["failed"] = failed;
  j["threads"] = threads;
  j["wall_time"] = wall_time;
  return j.dump(2) + "\n";
}

// ---------------------------------------------------------------- shards

std::string EnsembleShard::text() const { return std::to_string(k) + "/" + std::to_string(n); }

EnsembleShard parse_shard(const std::string& text) {
  EnsembleShard s;
  const std::size_t slash = text.find('/');
  const auto whole = [&](std::size_t from, std::size_t to, long& v) {
    const char* end = text.data() + to;
    const auto [p, ec] = std::from_chars(text.data() + from, end, v);
    return from < to && ec == std::errc() && p == end;
  };
  if (slash == std::string::npos || !whole(0, slash, s.k) || !whole(slash + 1, text.size(), s.n) || s.k < 1 ||
      s.k > s.n) {
    throw std::invalid_argument("shard '" + text + "': expected K/N, whole numbers with 1 <= K <= N");
  }
  return s;
}

std::vector<EnsembleSample> select_shard(const std::vector<EnsembleSample>& samples, const EnsembleShard& shard) {
  std::vector<EnsembleSample> out;
  for (const EnsembleSample& s : samples) {
    if (s.index % shard.n == shard.k - 1) out.push_back(s);
  }
  return out;
}

std::filesystem::path ensemble_sidecar_path(const std::filesystem::path& csv) {
  std::filesystem::path j = csv;
  return csv.extension() == ".csv" ? j.replace_extension(".json") : std::filesystem::path(csv.string() + ".json");
}

EnsembleProvenance ensemble_provenance(const EnsembleSpec& spec, const Scene& first, long total,
                                       std::optional<EnsembleShard> shard) {
  EnsembleProvenance p;
  p.samples_total = total;
  p.shard = shard;
  for (const std::string& f : {spec.file, spec.table}) {
    if (f.empty()) continue;
    std::ifstream in(f, std::ios::binary);
    std::ostringstream bytes;
    bytes << in.rdbuf();
    const std::string b = bytes.str();
    p.inputs.push_back({std::filesystem::absolute(f).lexically_normal().string(), b.size(), fnv1a64(b)});
  }
  for (const InputFile& f : first.inputs) p.inputs.push_back(f);
  return p;
}

namespace {

std::string read_whole(const std::string& path, const std::string& what) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw ConfigError(path + ": cannot read " + what);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

// The records of a CSV text, each with its line break (RFC 4180: a quoted
// field may hold line breaks; a doubled quote toggles twice).
std::vector<std::string> csv_records(const std::string& text) {
  std::vector<std::string> out;
  std::size_t start = 0;
  bool quoted = false;
  for (std::size_t i = 0; i < text.size(); ++i) {
    if (text[i] == '"') {
      quoted = !quoted;
    } else if (text[i] == '\n' && !quoted) {
      out.push_back(text.substr(start, i + 1 - start));
      start = i + 1;
    }
  }
  if (start < text.size()) out.push_back(text.substr(start));
  return out;
}

using OrderedJson = nlohmann::ordered_json;

// One shard's table and sidecar, as read.
struct ShardTable {
  std::string path, side;
  OrderedJson meta;    // its sidecar
  OrderedJson common;  // the sidecar without what differs between shards
  EnsembleShard shard;
  std::vector<std::string> records;  // the header, then a row per sample
};

ShardTable read_shard(const std::string& path) {
  // What differs between the shards of one ensemble; everything else in the
  // sidecars (the build, the spec, the columns, the input files) must agree.
  static const char* const kPerShard[] = {"shard", "samples", "failed", "threads", "wall_time"};
  ShardTable t;
  t.path = path;
  t.side = ensemble_sidecar_path(path).string();
  t.records = csv_records(read_whole(path, "the shard's table"));
  t.meta = OrderedJson::parse(read_whole(t.side, "the table's sidecar"), nullptr, false);
  if (!t.meta.is_object() || !t.meta.contains("written_by") || t.meta["written_by"] != "pumasim ensemble") {
    throw ConfigError(t.side + ": not a sidecar that pumasim ensemble wrote; expected the JSON beside a shard's table");
  }
  if (!t.meta.contains("shard") || !t.meta["shard"].is_string()) {
    throw ConfigError(t.side + ": shard: missing; expected the table of one shard (pumasim ensemble --shard K/N)");
  }
  try {
    t.shard = parse_shard(t.meta["shard"].get<std::string>());
  } catch (const std::invalid_argument& e) {
    throw ConfigError(t.side + ": " + e.what());
  }
  if (t.records.empty()) throw ConfigError(path + ": empty; expected a header and a row per sample");
  t.common = t.meta;
  for (const char* key : kPerShard) t.common.erase(key);
  return t;
}

// The first key in which two sidecars differ.
std::string first_difference(const OrderedJson& a, const OrderedJson& b) {
  for (const auto& [k, v] : a.items()) {
    if (!b.contains(k) || b[k] != v) return k;
  }
  for (const auto& [k, v] : b.items()) {
    if (!a.contains(k)) return k;
  }
  return "?";
}

// t belongs with the first shard: the same ensemble, build, columns and count of shards.
void check_same_ensemble(const ShardTable& t, const ShardTable& first) {
  if (t.shard.n != first.shard.n) {
    throw ConfigError(t.side + ": shard " + t.shard.text() + ": expected one of " + std::to_string(first.shard.n) +
                      " shards, as " + first.side + " says");
  }
  if (t.common != first.common) {
    throw ConfigError(t.side + ": " + first_difference(first.common, t.common) + " differs from " + first.side +
                      "'s: expected shards of one ensemble, run by one build");
  }
  if (t.records.front() != first.records.front()) {
    throw ConfigError(t.path + ": its header differs from " + first.path + "'s: expected the same columns");
  }
}

// The ensemble file as it is now is the one the shards read (by content).
void check_ensemble_file(const std::string& file, const ShardTable& first) {
  const std::string now = read_whole(file, "the ensemble file");
  const std::string abs = std::filesystem::absolute(file).lexically_normal().string();
  bool same = false;
  for (const OrderedJson& f : first.common.value("inputs", OrderedJson::array())) {
    if (f.value("path", "") == abs) same = f.value("fnv1a64", "") == hex64(fnv1a64(now));
  }
  if (!same) {
    throw ConfigError(file + ": not the file the shards were run from, or changed since (" + first.side +
                      "'s inputs); expected the ensemble file as the shards read it");
  }
}

// The rows of every shard, in sample order, checked to hold each sample once.
std::vector<std::pair<long, const std::string*>> merged_rows(const std::vector<ShardTable>& shards) {
  std::vector<std::pair<long, const std::string*>> rows;
  for (const ShardTable& t : shards) {
    for (std::size_t r = 1; r < t.records.size(); ++r) {
      long index = -1;
      const std::string& rec = t.records[r];
      const auto [p, ec] = std::from_chars(rec.data(), rec.data() + rec.size(), index);
      if (ec != std::errc() || p == rec.data() + rec.size() || *p != ',' || index < 0 ||
          index % t.shard.n != t.shard.k - 1) {
        throw ConfigError(t.path + ":" + std::to_string(r + 1) + ": sample: expected the index of one of shard " +
                          t.shard.text() + "'s samples");
      }
      rows.emplace_back(index, &rec);
    }
  }
  std::sort(rows.begin(), rows.end(), [](const auto& a, const auto& b) { return a.first < b.first; });
  for (std::size_t i = 0; i < rows.size(); ++i) {
    if (rows[i].first != static_cast<long>(i)) {
      throw ConfigError("merge: sample " + std::to_string(i) +
                        (rows[i].first > static_cast<long>(i) ? " is missing" : " appears twice") +
                        "; expected every sample of the ensemble once");
    }
  }
  const long total = shards.front().common.value("samples_total", 0L);
  if (static_cast<long>(rows.size()) != total) {
    throw ConfigError("merge: " + std::to_string(rows.size()) + " samples; expected " + std::to_string(total) +
                      " (samples_total in " + shards.front().side + ")");
  }
  return rows;
}

}  // namespace

MergedEnsemble merge_ensemble_shards(const std::vector<std::string>& tables, const std::string& ensemble_file) {
  if (tables.empty()) throw ConfigError("merge: no shard tables; expected the tables of the shards 1/N to N/N");
  std::vector<ShardTable> shards;
  std::vector<std::string> by_k;
  for (const std::string& path : tables) {
    shards.push_back(read_shard(path));
    const ShardTable& t = shards.back();
    if (shards.size() == 1) by_k.resize(static_cast<std::size_t>(t.shard.n));
    check_same_ensemble(t, shards.front());
    std::string& seen = by_k[static_cast<std::size_t>(t.shard.k - 1)];
    if (!seen.empty()) throw ConfigError(path + ": shard " + t.shard.text() + " is given twice (also " + seen + ")");
    seen = path;
  }
  std::string missing;
  for (std::size_t k = 0; k < by_k.size(); ++k) {
    if (by_k[k].empty()) {
      missing += (missing.empty() ? "" : ", ") + EnsembleShard{static_cast<long>(k) + 1, shards.front().shard.n}.text();
    }
  }
  if (!missing.empty()) {
    throw ConfigError("merge: shards missing: " + missing + "; expected every shard of " + std::to_string(by_k.size()));
  }
  if (!ensemble_file.empty()) check_ensemble_file(ensemble_file, shards.front());
  MergedEnsemble m;
  m.csv = shards.front().records.front();
  for (const auto& [i, rec] : merged_rows(shards)) m.csv += *rec;
  OrderedJson side = shards.front().common, from = OrderedJson::array();
  long failed = 0;
  double wall = 0;
  for (const ShardTable& t : shards) {
    failed += t.meta.value("failed", 0L);
    wall += t.meta.value("wall_time", 0.0);
    from.push_back({{"table", t.path},
                    {"shard", t.shard.text()},
                    {"threads", t.meta.value("threads", 0)},
                    {"wall_time", t.meta.value("wall_time", 0.0)}});
  }
  side["samples"] = side.value("samples_total", 0L);
  side["failed"] = failed;
  side["wall_time"] = wall;
  side["merged_from"] = from;
  m.sidecar = side.dump(2) + "\n";
  return m;
}

}  // namespace pumasim
