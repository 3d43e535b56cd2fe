// Ensembles (simulation/ensemble.hpp): the samples' draws (replayable, from
// the distributions they claim: moments against their closed forms), a
// sample re-run alone equal bit for bit to its row, failures as rows, the
// table's numbers reading back exactly, and the ensemble file's errors. The
// same ensemble on 1, 2 and 8 threads: tests/test_threads.cpp.
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <numbers>
#include <sstream>
#include <string>
#include <vector>

#include "core/errors.hpp"
#include "simulation/ensemble.hpp"
#include "tests/cli_capture.hpp"
#include "tests/ensemble_helpers.hpp"

namespace pumasim {
namespace {

using Kind = EnsembleFactor::Kind;

const std::string kScenesDir = PUMASIM_SCENES_DIR;

EnsembleSpec one_factor(EnsembleFactor f, long samples) {
  EnsembleSpec s;
  s.samples = samples;
  s.seed = 7;
  s.factors.push_back(std::move(f));
  return s;
}

std::vector<double> drawn(const EnsembleSpec& s) {
  std::vector<double> x;
  for (const EnsembleSample& e : draw_samples(s)) x.push_back(std::strtod(e.values[0].c_str(), nullptr));
  return x;
}

double mean_of(const std::vector<double>& x) {
  double m = 0;
  for (double v : x) m += v / static_cast<double>(x.size());
  return m;
}

double variance_of(const std::vector<double>& x) {
  const double m = mean_of(x);
  double v = 0;
  for (double e : x) v += (e - m) * (e - m) / static_cast<double>(x.size() - 1);
  return v;
}

// Sample k drawn alone is sample k of the whole draw; samples differ; a
// different seed gives different samples; the values read back exactly.
TEST(EnsembleDraws, EachSampleIsReplayableAlone) {
  const EnsembleSpec s = testing::small_ensemble(kScenesDir, 50);
  const std::vector<EnsembleSample> all = draw_samples(s);
  ASSERT_EQ(all.size(), 50u);
  for (long k : {0L, 1L, 17L, 49L}) {
    const EnsembleSample alone = draw_sample(s, k);
    EXPECT_EQ(alone.values, all[static_cast<std::size_t>(k)].values) << k;
    EXPECT_EQ(alone.seed, all[static_cast<std::size_t>(k)].seed) << k;
  }
  EXPECT_NE(all[0].values, all[1].values);
  EnsembleSpec other = s;
  other.seed = s.seed + 1;
  EXPECT_NE(draw_sample(other, 0).values, all[0].values);
  for (const std::string& v : all[3].values) {
    const double x = std::strtod(v.c_str(), nullptr);
    char buf[40];
    std::snprintf(buf, sizeof buf, "%.17g", x);
    EXPECT_EQ(v, buf);  // 17 significant digits: the text is the double
  }
}

// Moments against their closed forms, over 40,000 draws: within 5 standard
// errors (a false failure about once in 3.5 million). Uniform(a, b): mean
// (a+b)/2, variance (b-a)^2/12, every draw in [a, b). Log-uniform: ln x
// uniform on [ln a, ln b). Normal(mu, sd): mean mu, variance sd^2 (standard
// error of the sample variance sd^2 sqrt(2/(n-1))). Choice: each of the
// values with probability 1/k.
TEST(EnsembleDraws, DistributionsHaveTheirClosedFormMoments) {
  const long n = 40000;
  const double se = 5.0 / std::sqrt(static_cast<double>(n));
  {
    const auto x = drawn(one_factor({.key = "a.b", .kind = Kind::kUniform, .a = -1.0, .b = 3.0}, n));
    for (double v : x) ASSERT_TRUE(v >= -1.0 && v < 3.0) << v;
    const double sd = 4.0 / std::sqrt(12.0);
    EXPECT_NEAR(mean_of(x), 1.0, se * sd);
    EXPECT_NEAR(variance_of(x), sd * sd, 5 * sd * sd * std::sqrt(0.8 / n));  // var of U's sample variance: 4/5 s^4/n
  }
  {
    auto x = drawn(one_factor({.key = "a.b", .kind = Kind::kLogUniform, .a = 1e-3, .b = 1e1}, n));
    for (double& v : x) {
      ASSERT_TRUE(v >= 1e-3 && v < 1e1) << v;
      v = std::log(v);
    }
    const double lo = std::log(1e-3), hi = std::log(1e1), sd = (hi - lo) / std::sqrt(12.0);
    EXPECT_NEAR(mean_of(x), (lo + hi) / 2, se * sd);
  }
  {
    const auto x = drawn(one_factor({.key = "a.b", .kind = Kind::kNormal, .a = 2.0, .b = 0.5}, n));
    EXPECT_NEAR(mean_of(x), 2.0, se * 0.5);
    EXPECT_NEAR(variance_of(x), 0.25, 5 * 0.25 * std::sqrt(2.0 / (n - 1)));
    long beyond = 0;  // P(|z| > 2) = 0.0455 (erfc(sqrt 2))
    for (double v : x) beyond += std::abs(v - 2.0) > 1.0;
    const double p = std::erfc(std::numbers::sqrt2);
    EXPECT_NEAR(static_cast<double>(beyond) / n, p, 5 * std::sqrt(p * (1 - p) / n));
  }
  {
    EnsembleFactor f{.key = "a.b", .kind = Kind::kChoice};
    f.choices = {"1", "\"two\"", "3.5"};
    long counts[3] = {0, 0, 0};
    for (const EnsembleSample& e : draw_samples(one_factor(f, n))) {
      for (int i = 0; i < 3; ++i) counts[i] += e.values[0] == f.choices[static_cast<std::size_t>(i)];
    }
    EXPECT_EQ(counts[0] + counts[1] + counts[2], n);
    for (long c : counts) EXPECT_NEAR(static_cast<double>(c) / n, 1.0 / 3, 5 * std::sqrt(2.0 / 9 / n));
  }
}

// A correlated pair of normals: the partner's draws are those it has alone;
// the pair's sample correlation is rho within 5 standard errors (the large-n
// standard error of Pearson's r for a bivariate normal, (1 - rho^2) / sqrt(n);
// Fisher 1915), and each member keeps its own mean and sd.
TEST(EnsembleDraws, ACorrelatedPairHasItsCorrelation) {
  const long n = 40000;
  for (const double rho : {0.6, -0.9, 0.0, 1.0}) {
    EnsembleSpec s = one_factor({.key = "a.b", .kind = Kind::kNormal, .a = 2.0, .b = 0.5}, n);
    const std::vector<double> alone = drawn(s);
    s.factors.push_back({.key = "c.d", .kind = Kind::kNormal, .a = -1.0, .b = 3.0, .partner = 0, .rho = rho});
    std::vector<double> x, y;
    for (const EnsembleSample& e : draw_samples(s))
      x.push_back(std::stod(e.values[0])), y.push_back(std::stod(e.values[1]));
    EXPECT_EQ(x, alone) << rho;
    const double mx = mean_of(x), my = mean_of(y);
    double sxy = 0;
    for (long k = 0; k < n; ++k) sxy += (x[static_cast<std::size_t>(k)] - mx) * (y[static_cast<std::size_t>(k)] - my);
    const double r = sxy / (n - 1) / std::sqrt(variance_of(x) * variance_of(y));
    EXPECT_NEAR(r, rho, 5 * std::max(1 - rho * rho, 1e-3) / std::sqrt(static_cast<double>(n))) << rho;
    EXPECT_NEAR(my, -1.0, 5 * 3.0 / std::sqrt(static_cast<double>(n))) << rho;
    EXPECT_NEAR(variance_of(y), 9.0, 5 * 9.0 * std::sqrt(2.0 / (n - 1))) << rho;
  }
}

// Sample k run alone (as `pumasim ensemble --sample K` does) is its row of
// the whole ensemble, bit for bit; the varied values reached the plant (the
// samples' step counts or path errors differ).
TEST(Ensemble, ASampleRunAloneIsItsRowBitForBit) {
  const EnsembleSpec s = testing::small_ensemble(kScenesDir, 4);
  const std::vector<SampleResult> all = run_ensemble(s, draw_samples(s), 2);
  ASSERT_EQ(all.size(), 4u);
  for (const SampleResult& r : all) ASSERT_TRUE(r.ok) << r.failure;
  const std::vector<SampleResult> alone = run_ensemble(s, {draw_sample(s, 2)}, 1);
  ASSERT_EQ(alone.size(), 1u);
  testing::expect_same_result(alone[0], all[2], "alone");
  EXPECT_FALSE(testing::same_bits(all[0].figures.max_path_error, all[1].figures.max_path_error));
}

// A value the scene reader refuses (a negative resistance) is a row with
// failure_kind "input" and the reader's message; the other samples run.
TEST(Ensemble, ARefusedSampleIsARowWithItsReason) {
  EnsembleSpec s = testing::small_ensemble(kScenesDir, 0);
  s.factors = {{.key = "motor.resistance", .kind = Kind::kChoice, .choices = {"-1.0"}}};
  std::vector<EnsembleSample> samples = {draw_sample(s, 0)};
  EnsembleSample good = samples[0];
  good.index = 1, good.values = {"2.0"};
  samples.push_back(good);
  const std::vector<SampleResult> r = run_ensemble(s, samples, 2);
  ASSERT_EQ(r.size(), 2u);
  EXPECT_FALSE(r[0].ok);
  EXPECT_EQ(r[0].failure_kind, "input");
  EXPECT_NE(r[0].failure.find("motor.resistance"), std::string::npos) << r[0].failure;
  EXPECT_TRUE(r[1].ok) << r[1].failure;
  // The table has both rows; the failure's reason is one quoted field.
  const std::string csv = ensemble_csv(r);
  std::istringstream lines(csv);
  std::string header, row0, row1, extra;
  std::getline(lines, header), std::getline(lines, row0), std::getline(lines, row1);
  EXPECT_FALSE(std::getline(lines, extra) && !extra.empty());
  EXPECT_EQ(header.rfind("sample,seed,motor.resistance,ok,failure_kind,", 0), 0u) << header;
  EXPECT_NE(row0.find(",0,input,"), std::string::npos) << row0;
  EXPECT_NE(row1.find(",1,,"), std::string::npos) << row1;
}

std::filesystem::path write_file(const std::string& name, const std::string& text) {
  const auto dir = std::filesystem::temp_directory_path() / "pumasim_test_ensemble";
  std::filesystem::create_directories(dir);
  const auto p = dir / name;
  std::ofstream(p) << text;
  return p;
}

void expect_config_error(const std::string& text, const std::vector<std::string>& parts) {
  const auto p = write_file("bad.toml", text);
  try {
    read_ensemble_file(p.string());
    ADD_FAILURE() << "expected a ConfigError for:\n" << text;
  } catch (const ConfigError& e) {
    const std::string msg = e.what();
    EXPECT_NE(msg.find(p.string()), std::string::npos) << msg;
    for (const std::string& part : parts) EXPECT_NE(msg.find(part), std::string::npos) << part << " in: " << msg;
  }
}

// The ensemble file: every key read, the scene resolved against its folder;
// an unknown key, a wrong type or a value out of range names the file, the
// line and the key.
TEST(EnsembleFile, ReadsEveryKeyAndRefusesBadOnesNamingFileLineAndKey) {
  const std::string head = "scene = \"" + kScenesDir + "/paper_slow_viscous.toml\"\nsamples = 3\n";
  const auto p = write_file("good.toml", head +
                                             "seed = 5\nset = [\"friction.viscous=0.001\"]\n[run]\n"
                                             "integrator = \"cvode-bdf\"\nrtol = 1e-5\nt_end = 0.5\n"
                                             "max_wall = 10\n[[vary]]\nkey = \"motor.resistance\"\n"
                                             "distribution = \"choice\"\nvalues = [1.5, 2.5]\n");
  const EnsembleSpec s = read_ensemble_file(p.string());
  EXPECT_EQ(s.samples, 3);
  EXPECT_EQ(s.seed, 5u);
  EXPECT_EQ(s.sets, std::vector<std::string>{"friction.viscous=0.001"});
  EXPECT_EQ(*s.options.integrator, "cvode-bdf");
  EXPECT_EQ(*s.options.rtol, 1e-5);
  ASSERT_EQ(s.factors.size(), 1u);
  EXPECT_EQ(s.factors[0].choices, (std::vector<std::string>{"1.5", "2.5"}));
  const auto relative = write_file("relative.toml", "scene = \"x.toml\"\nsamples = 1\n");
  EXPECT_EQ(read_ensemble_file(relative.string()).scene, (relative.parent_path() / "x.toml").string());

  expect_config_error(head + "sample = 3\n", {":3:", "unknown key 'sample'"});
  expect_config_error(head + "[run]\nrtol = \"tight\"\n", {":4:", "run.rtol", "expected"});
  expect_config_error(head + "[[vary]]\nkey = \"motor.resistance\"\ndistribution = \"normal\"\nmean = 2\nsd = -1\n",
                      {"vary", "sd", "a number > 0"});
  expect_config_error(head + "[[vary]]\nkey = \"motor.resistance\"\ndistribution = \"gaussian\"\n",
                      {"distribution", "normal", "log-uniform"});
  expect_config_error(head + "[[vary]]\nkey = \"r\"\ndistribution = \"uniform\"\nlow = 1\nhigh = 2\n",
                      {"key", "section.key"});
  expect_config_error(head + "[[vary]]\nkey = \"a.b\"\ndistribution = \"uniform\"\nlow = 2\nhigh = 1\n", {"high"});
  expect_config_error("scene = \"x.toml\"\nsamples = 2.5\n", {"samples", "whole"});

  // Correlated pairs: read, and refused unless of two normals, the partner
  // earlier and in no other pair, the correlation in [-1, 1].
  const std::string r = "[[vary]]\nkey = \"motor.resistance\"\ndistribution = \"normal\"\nmean = 2\nsd = 0.2\n";
  const std::string u = "[[vary]]\nkey = \"amplifier.gain\"\ndistribution = \"uniform\"\nlow = 3\nhigh = 5\n";
  const auto pair = [](const std::string& with, const std::string& rho) {
    return "[[vary]]\nkey = \"motor.inductance\"\ndistribution = \"normal\"\nmean = 0.002\nsd = 0.0003\n"
           "correlate_with = \"" +
           with + "\"\ncorrelation = " + rho + "\n";
  };
  const EnsembleSpec paired =
      read_ensemble_file(write_file("pair.toml", head + u + r + pair("motor.resistance", "0.6")).string());
  ASSERT_EQ(paired.factors.size(), 3u);
  EXPECT_EQ(paired.factors[2].partner, 1);
  EXPECT_EQ(paired.factors[2].rho, 0.6);
  EXPECT_EQ(paired.factors[0].partner, -1);
  expect_config_error(head + r + pair("motor.resistance", "1.5"), {"correlation", "1"});
  expect_config_error(head + r + pair("motor.resistanc", "0.5"), {"correlate_with", "earlier"});
  expect_config_error(head + u + pair("amplifier.gain", "0.5"), {"correlate_with", "normal", "uniform"});
  expect_config_error(head + pair("motor.resistance", "0.5") + r, {"correlate_with", "earlier"});
  expect_config_error(head + r + pair("motor.resistance", "0.5") +
                          "[[vary]]\nkey = \"motor.torque_constant\"\ndistribution = \"normal\"\nmean = 0.2\n"
                          "sd = 0.01\ncorrelate_with = \"motor.resistance\"\ncorrelation = 0.1\n",
                      {"correlate_with", "already paired"});
  expect_config_error(head + r +
                          "[[vary]]\nkey = \"a.b\"\ndistribution = \"normal\"\nmean = 0\nsd = 1\n"
                          "correlation = 0.5\n",
                      {"correlation", "correlate_with"});
}

// `pumasim ensemble`: the table and its sidecar, --sample K's row equal to
// row K but for the wall time, an existing table replaced only with --force,
// a file pumasim did not write never replaced, and a bad file exit status 2
// with nothing written.
TEST(EnsembleCli, WritesTheTableReplaysARowAndNeverOverwritesWhatItDidNotWrite) {
  const auto dir = std::filesystem::temp_directory_path() / "pumasim_test_ensemble_cli";
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  const auto file = dir / "e.toml";
  std::ofstream(file) << "scene = \"" << kScenesDir << "/paper_slow_viscous.toml\"\nsamples = 3\nseed = 4\n"
                      << "[run]\nintegrator = \"cvode-bdf\"\nt_end = 0.05\n[[vary]]\nkey = \"amplifier.gain\"\n"
                      << "distribution = \"uniform\"\nlow = 3.5\nhigh = 4.5\n";
  const std::string csv = (dir / "t.csv").string();
  const auto r = testing::cli({"ensemble", file.string(), "--out", csv, "--threads", "2", "-q"});
  ASSERT_EQ(r.status, 0) << r.err;
  std::ifstream in(csv);
  std::vector<std::string> lines;
  for (std::string l; std::getline(in, l);) lines.push_back(l);
  ASSERT_EQ(lines.size(), 4u);
  ASSERT_TRUE(std::filesystem::exists(dir / "t.json"));
  // Row 1 alone, on stdout: the same fields but wall_time (the 13th column).
  const auto one = testing::cli({"ensemble", file.string(), "--sample", "1", "-q"});
  ASSERT_EQ(one.status, 0) << one.err;
  const auto fields = [](const std::string& line) {
    std::vector<std::string> f;
    std::stringstream ss(line);
    for (std::string x; std::getline(ss, x, ',');) f.push_back(x);
    if (!line.empty() && line.back() == ',') f.emplace_back();
    return f;
  };
  std::istringstream o(one.out);
  std::string header, row;
  std::getline(o, header), std::getline(o, row);
  EXPECT_EQ(header, lines[0]);
  auto a = fields(row), b = fields(lines[2]);
  ASSERT_EQ(a.size(), b.size());
  const std::vector<std::string> names = fields(header);
  const auto wall = std::find(names.begin(), names.end(), "wall_time") - names.begin();
  ASSERT_GT(wall, 0);
  for (std::size_t i = 0; i < a.size(); ++i) {
    if (static_cast<long>(i) != wall) {
      EXPECT_EQ(a[i], b[i]) << "column " << i;
    }
  }
  // Replaced only with --force.
  EXPECT_EQ(testing::cli({"ensemble", file.string(), "--out", csv, "-q"}).status, 2);
  EXPECT_EQ(testing::cli({"ensemble", file.string(), "--out", csv, "-q", "--force"}).status, 0);
  // A file of the user's is never replaced, --force or not.
  const std::string mine = (dir / "mine.csv").string();
  std::ofstream(mine) << "my data\n";
  const auto refused = testing::cli({"ensemble", file.string(), "--out", mine, "-q", "--force"});
  EXPECT_EQ(refused.status, 2);
  EXPECT_NE(refused.err.find("not written by pumasim ensemble"), std::string::npos) << refused.err;
  std::ifstream kept(mine);
  std::string first;
  std::getline(kept, first);
  EXPECT_EQ(first, "my data");
  // A bad ensemble file: exit status 2, the file and key named, nothing written.
  const auto bad = dir / "bad.toml";
  std::ofstream(bad) << "scene = \"x.toml\"\nsamples = 3\nthreads = 2\n";
  const std::string none = (dir / "none.csv").string();
  const auto b2 = testing::cli({"ensemble", bad.string(), "--out", none});
  EXPECT_EQ(b2.status, 2);
  EXPECT_NE(b2.err.find("bad.toml:3"), std::string::npos) << b2.err;
  EXPECT_NE(b2.err.find("threads"), std::string::npos) << b2.err;
  EXPECT_FALSE(std::filesystem::exists(none));
  std::filesystem::remove_all(dir);
}

// A table of given samples: one per row, the header's keys, values as TOML
// text (a quoted string's quotes CSV-escaped); a row of another width or an
// empty field names the file and the line. Run, each row's values reach the
// scene (the two gains give two tracking errors; the same gain twice, the
// same result bit for bit).
TEST(EnsembleTable, RowsAreSamplesAndBadRowsNameTheirLine) {
  const auto t =
      write_file("t.csv", "amplifier.gain,scene.name\n4.0,\"\"\"a\"\"\"\n3.5,\"\"\"b\"\"\"\n4.0,\"\"\"a\"\"\"\n");
  const std::vector<EnsembleSample> s = read_sample_table(t.string());
  ASSERT_EQ(s.size(), 3u);
  EXPECT_EQ(s[1].index, 1);
  EXPECT_EQ(s[1].keys, (std::vector<std::string>{"amplifier.gain", "scene.name"}));
  EXPECT_EQ(s[1].values, (std::vector<std::string>{"3.5", "\"b\""}));
  EnsembleSpec spec = testing::small_ensemble(kScenesDir, 0);
  spec.factors.clear();
  const std::vector<SampleResult> r = run_ensemble(spec, s, 2);
  for (const SampleResult& x : r) ASSERT_TRUE(x.ok) << x.failure;
  EXPECT_FALSE(testing::same_bits(r[0].figures.max_path_error, r[1].figures.max_path_error));
  SampleResult again = r[0];
  again.sample.index = 2;
  testing::expect_same_result(r[2], again, "the same row again");
  const auto expect_error = [](const std::string& text, const std::string& part) {
    const auto p = write_file("bad.csv", text);
    try {
      read_sample_table(p.string());
      ADD_FAILURE() << text;
    } catch (const ConfigError& e) {
      EXPECT_NE(std::string(e.what()).find(p.string() + part), std::string::npos) << e.what();
    }
  };
  expect_error("amplifier.gain,motor.resistance\n4.0,2.0\n4.0\n", ":3: 1 fields; expected 2");
  expect_error("amplifier.gain\n\n4.0\n,\n", ":4:");
  expect_error("gain\n4.0\n", ":1: header 'gain'");
  expect_error("amplifier.gain\n", ": no rows");
}

// Shards (sweep.py's --shard K/N contract): K-1 modulo N, the shares
// disjoint and together every sample; their tables merged equal the one
// table a single process writes, every field but wall_time (the
// integration's own clock time) byte for byte; a missing, repeated or
// foreign shard is refused, naming the file. A small ensemble for them: 7
// samples of the viscous scene.
void write_shard_ensemble(const std::filesystem::path& file, long seed) {
  std::ofstream(file) << "scene = \"" << kScenesDir << "/paper_slow_viscous.toml\"\nsamples = 7\nseed = " << seed
                      << "\n[run]\nintegrator = \"cvode-bdf\"\nt_end = 0.03\n[[vary]]\nkey = \"amplifier.gain\"\n"
                      << "distribution = \"uniform\"\nlow = 3.5\nhigh = 4.5\n";
}

TEST(EnsembleShards, AreKMinusOneModuloNDisjointAndTogetherEverySample) {
  EXPECT_EQ(parse_shard("2/3").k, 2);
  EXPECT_EQ(parse_shard("2/3").n, 3);
  for (const char* bad : {"0/3", "4/3", "3", "1/0", "a/b", "1/3x", "-1/3", ""}) {
    EXPECT_THROW(parse_shard(bad), std::invalid_argument) << bad;
  }
  const auto file = std::filesystem::temp_directory_path() / "pumasim_test_shard_partition.toml";
  write_shard_ensemble(file, 4);
  const std::vector<EnsembleSample> all = draw_samples(read_ensemble_file(file.string()));
  std::vector<long> seen;
  for (long k = 1; k <= 3; ++k) {
    for (const EnsembleSample& s : select_shard(all, {k, 3})) {
      EXPECT_EQ(s.index % 3, k - 1);
      seen.push_back(s.index);
    }
  }
  std::sort(seen.begin(), seen.end());
  EXPECT_EQ(seen, (std::vector<long>{0, 1, 2, 3, 4, 5, 6}));
  std::filesystem::remove(file);
}

TEST(EnsembleShards, MergeIntoTheSingleProcessTableAndRefuseForeignOrMissingShards) {
  const auto dir = std::filesystem::temp_directory_path() / "pumasim_test_ensemble_shards";
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  const auto file = dir / "e.toml";
  const auto write_file = [&](long seed) { write_shard_ensemble(file, seed); };
  write_file(4);
  const std::string whole = (dir / "whole.csv").string();
  ASSERT_EQ(testing::cli({"ensemble", file.string(), "--out", whole, "--threads", "1", "-q"}).status, 0);
  std::vector<std::string> shards;
  for (int k : {3, 1, 2}) {  // in any order
    shards.push_back((dir / ("s" + std::to_string(k) + ".csv")).string());
    const auto r = testing::cli({"ensemble", file.string(), "--shard", std::to_string(k) + "/3", "--out", shards.back(),
                                 "--threads", "2", "-q"});
    ASSERT_EQ(r.status, 0) << r.err;
  }
  const std::string merged = (dir / "merged.csv").string();
  std::vector<std::string> args = {"ensemble", file.string(), "--merge"};
  args.insert(args.end(), shards.begin(), shards.end());
  args.insert(args.end(), {"--out", merged, "-q"});
  const auto m = testing::cli(args);
  ASSERT_EQ(m.status, 0) << m.err;
  // Every field but wall_time equal, byte for byte (no field here is quoted).
  const auto masked = [](const std::string& path) {
    std::ifstream in(path);
    std::vector<std::vector<std::string>> rows;
    for (std::string l; std::getline(in, l);) {
      std::vector<std::string> f;
      std::stringstream ss(l);
      for (std::string x; std::getline(ss, x, ',');) f.push_back(x);
      if (!l.empty() && l.back() == ',') f.emplace_back();
      rows.push_back(f);
    }
    if (rows.empty()) return rows;
    const auto wall = std::find(rows[0].begin(), rows[0].end(), "wall_time") - rows[0].begin();
    for (std::size_t r = 1; r < rows.size(); ++r) rows[r].at(static_cast<std::size_t>(wall)) = "";
    return rows;
  };
  const auto a = masked(whole), b = masked(merged);
  ASSERT_EQ(a.size(), 8u);
  EXPECT_EQ(a, b);
  const nlohmann::json side = nlohmann::json::parse(std::ifstream(dir / "merged.json"));
  EXPECT_EQ(side["samples"], 7);
  EXPECT_EQ(side["merged_from"].size(), 3u);

  // Refused: a shard missing, one given twice, the output one of the shards.
  const auto refuse = [&](std::vector<std::string> tables, const std::string& what) {
    std::vector<std::string> a2 = {"ensemble", file.string(), "--merge"};
    a2.insert(a2.end(), tables.begin(), tables.end());
    const auto r = testing::cli(a2);
    EXPECT_EQ(r.status, 2) << what;
    EXPECT_NE(r.err.find(what), std::string::npos) << r.err;
  };
  refuse({shards[0], shards[1]}, "shards missing: 2/3");
  refuse({shards[0], shards[1], shards[2], shards[1]}, "given twice");
  // A shard of another ensemble: the file run again with another seed.
  write_file(5);
  const std::string other = (dir / "other.csv").string();
  ASSERT_EQ(testing::cli({"ensemble", file.string(), "--shard", "2/3", "--out", other, "-q"}).status, 0);
  refuse({shards[0], other, shards[2]}, "differs from");
  // The ensemble file changed since the shards ran: refused, naming it.
  refuse({shards[0], shards[1], shards[2]}, "not the file the shards were run from");
  EXPECT_EQ(testing::cli({"ensemble", file.string(), "--shard", "8/7", "-q"}).status, 2);
  EXPECT_EQ(testing::cli({"ensemble", file.string(), "--shard", "8/8", "-q"}).status, 2);  // no sample: 7 of them
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace pumasim
