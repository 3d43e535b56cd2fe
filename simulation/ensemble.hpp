// Many runs of one scene (issue 35): an ensemble is a scene, the options of
// its runs, and samples, each a set of scene overrides ("section.key=value",
// as `--set` takes them). The samples come from an ensemble file's factors
// (a distribution per varied key), each drawn from its own generator seeded
// from the ensemble's seed and the sample's index, so that any sample
// re-runs alone with exactly its result; or they are given (a table, the
// Python module). run_ensemble runs them on a pool of threads through the
// front door (run(), simulation/run.hpp), each with its own plant: samples
// share nothing mutable, so a sample's result does not depend on the number
// of threads or on which thread ran it (tests/test_threads.cpp, under
// ThreadSanitizer). The result is one table: a row per sample, its inputs
// and outputs, a failed run as a row with its reason.
#pragma once

#include <cstdint>
#include <filesystem>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "integrators/integrator.hpp"
#include "models/robot/input_files.hpp"
#include "simulation/run.hpp"

namespace pumasim {

// One varied scene key and its distribution.
struct EnsembleFactor {
  enum class Kind { kNormal, kUniform, kLogUniform, kChoice };
  std::string key;  // "section.key", as `--set` takes it
  Kind kind = Kind::kUniform;
  double a = 0, b = 0;               // normal: mean, sd; uniform and log-uniform: low, high
  std::vector<std::string> choices;  // choice: the values as TOML text, each equally likely
  // A correlated pair of normals: this normal factor's standard normal is
  // rho z_p + sqrt(1 - rho^2) z, z_p that of `partner` (an earlier normal
  // factor, in no other pair; its draw unchanged), z its own draw. Pairs
  // only, so that every correlation matrix is valid (positive semi-definite).
  int partner = -1;  // the earlier factor's index (-1: independent)
  double rho = 0;    // the correlation, in [-1, 1]
};

// "normal", "uniform", "log-uniform", "choice".
const char* factor_kind_name(EnsembleFactor::Kind kind);

struct EnsembleSpec {
  std::string file;               // the ensemble file ("" when built in code)
  std::string scene;              // the scene file (relative to the ensemble file's folder when read from one)
  std::vector<std::string> sets;  // overrides common to every sample, applied before the sample's
  RunOptions options;             // the runs' integrator, tolerances, end time, budgets
  long samples = 0;               // how many to draw from the factors
  std::uint64_t seed = 0;
  bool final_state = false;  // the table also gives each run's final state (columns final.<state>)
  std::vector<EnsembleFactor> factors;
  std::string table;  // the samples' table, when they were given as one (read_sample_table)
};

struct EnsembleSample {
  long index = 0;
  std::uint64_t seed = 0;                 // its generator's seed (0 for a given sample)
  std::vector<std::string> keys;          // the overridden keys, "section.key"
  std::vector<std::string> values;        // their values as TOML text (numbers with 17 significant digits)
  std::vector<std::string> sets() const;  // "key=value" each
};

// Reads an ensemble file; ConfigError naming the file, line and key for an
// unknown key, a wrong type or a value out of range (a distribution's
// parameters included). The scene's path is resolved against the file's
// folder.
EnsembleSpec read_ensemble_file(const std::string& path);

// Sample k of the spec's factors: its seed is a hash of (spec.seed, k) and
// its generator (std::mt19937_64, whose output the standard fixes) draws each
// factor in order, by transforms written here (not the library's
// distributions, whose algorithms the standard leaves open): any sample is
// reproducible alone, on any standard library.
EnsembleSample draw_sample(const EnsembleSpec& spec, long k);
std::vector<EnsembleSample> draw_samples(const EnsembleSpec& spec);

// Given samples: a CSV table (RFC 4180) whose header names the scene keys
// ("section.key") and each of whose rows is a sample, its fields the values
// as TOML text (numbers, true/false, or quoted strings). Sample k is row k
// (seed 0). ConfigError naming the file and line for a row of another width,
// an empty field, a header key without a section, or no rows.
std::vector<EnsembleSample> read_sample_table(const std::string& path);

struct SampleResult {
  EnsembleSample sample;
  bool ok = false;
  std::string failure_kind;  // the run's ("budget", "unstable", "integrator", "interrupted") or "input"
  std::string failure;       // its reason ("" when ok)
  double t_final = 0;
  IntegratorStats stats;
  RunFigures figures;                    // figures.final_state: the last output's state
  std::vector<std::string> state_names;  // the plant's, for the final state's columns
  double wall_time = 0;                  // [s] the integration's own (RunResult::wall_time)
};

// How far the ensemble is: called from one thread at a time.
using EnsembleProgress = std::function<void(long done, long failed, long total)>;

// Runs every sample (threads >= 1; more threads than samples are not
// started) and returns their results in the samples' order. A sample whose
// overrides the scene reader refuses is a row with failure_kind "input"; a
// run that fails is a row with its reason. `cancel`, when set and true,
// stops starting new samples (those left are rows of kind "interrupted").
std::vector<SampleResult> run_ensemble(const EnsembleSpec& spec, const std::vector<EnsembleSample>& samples,
                                       int threads, const EnsembleProgress& progress = {},
                                       const bool* cancel = nullptr);

// The table: a header, then a row per sample; numbers with 17 significant
// digits (they read back exactly), text fields quoted as RFC 4180 says. With
// final_state, a column final.<state> per state (empty in a failed row).
std::string ensemble_csv(const std::vector<SampleResult>& results, bool final_state = false);

// A share of an ensemble's samples, sweep.py's --shard contract: "K/N"
// (1 <= K <= N) takes the samples whose index is K-1 modulo N. Shards of one
// ensemble, each run anywhere (GNU parallel, a Slurm job array), merge into
// the table one process writes (merge_ensemble_shards): every field equal,
// byte for byte, but wall_time (the integration's own clock time).
struct EnsembleShard {
  long k = 1, n = 1;
  std::string text() const;  // "K/N"
};

// "K/N" as a shard; std::invalid_argument for anything else, or K outside 1..N.
EnsembleShard parse_shard(const std::string& text);

// The samples of the shard, in their order.
std::vector<EnsembleSample> select_shard(const std::vector<EnsembleSample>& samples, const EnsembleShard& shard);

// What a sidecar records beside the spec: how many samples the ensemble has
// (a shard's table holds fewer), the shard, and the files the ensemble read
// (the ensemble file, the table, the first sample's scene with its robot and
// side files), by content: shards merge only when these agree.
struct EnsembleProvenance {
  long samples_total = 0;  // 0: the results' count
  std::optional<EnsembleShard> shard;
  std::vector<InputFile> inputs;
};

// PATH.json beside PATH.csv (PATH.csv.json for another name): a table's sidecar.
std::filesystem::path ensemble_sidecar_path(const std::filesystem::path& csv);

// The shard tables of one ensemble (each PATH.csv with its sidecar) as one
// table, rows in sample order, and its sidecar (the shards' common record,
// with each shard's threads and wall time). ConfigError naming the file when
// a table or its sidecar is missing or not pumasim ensemble's, is not a
// shard, belongs to another ensemble (any recorded field or input file
// differs, the file `ensemble_file` as it is now included, when given), when
// a shard is missing or given twice, or when the rows do not hold every
// sample exactly once.
struct MergedEnsemble {
  std::string csv, sidecar;
};
MergedEnsemble merge_ensemble_shards(const std::vector<std::string>& tables, const std::string& ensemble_file = "");

// The JSON sidecar: what wrote the table, the spec (scene, options, seed,
// factors), the provenance (the ensemble's sample count, the shard, the
// files read), every column's meaning and unit, the counts and the wall time.
std::string ensemble_sidecar(const EnsembleSpec& spec, const std::vector<SampleResult>& results, int threads,
                             double wall_time, const EnsembleProvenance& provenance = {});

// The provenance of an ensemble of `total` samples (run as `shard`, if set):
// the ensemble file and the table (spec.file, spec.table) by their bytes,
// then the files the first sample's scene read (first.inputs).
EnsembleProvenance ensemble_provenance(const EnsembleSpec& spec, const Scene& first, long total,
                                       std::optional<EnsembleShard> shard = std::nullopt);

}  // namespace pumasim
