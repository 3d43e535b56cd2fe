#!/usr/bin/env python3
"""Adding an integrator or a back-end is one file plus one row: the proof.

In a scratch copy of the tree (the working tree's files as git lists them;
the tree itself is not touched), this adds
  - integrators/scratch_heun.cpp, Heun's method (the explicit trapezoidal
    rule, order 2, stability polynomial 1 + z + z^2/2: Hairer, Norsett &
    Wanner I, Sec. II.1 and IV.2), and beside it the same method with wrong
    weights (order 1) under another name; and their rows, each a factory
    declaration and an entry in integrators/registry.cpp's table;
  - models/dynamics/backends/scratch_rnea.{hpp,cpp}, a back-end on the
    paper's probing algorithm under its own name,
with no other edit (the scratch build's subset of back-ends, PUMASIM_BACKENDS,
then names the new one: a setting of that build). It then builds the suites that iterate
the registries (every test source with a Registry suite: any number of
joints, integrators, conformance; the back-ends' agreement and identities;
the no-allocation guard) and checks that
  1. the new entries take part: every registry-parameterised suite has a
     scratch_heun instance, and each of them passes, or skips for a reason on
     record (ALLOWED_SKIPS: a fixed-step method has no tolerance); the
     registry's tests and the no-allocation guard pass with the new back-end
     among the built ones;
  2. no test skips them silently: the wrong-weights integrator fails its
     order test, and the back-end made wrong (PUMASIM_SCRATCH_WRONG: its mass
     matrix's first entry doubled) fails the back-end agreement.
What it does not run: the process-level CTests (the arm scenes, the extreme
runs, the observed order), and Docs.ReferenceIsCurrent, which asks for
scripts/gen_reference.py to be re-run (the reference pages list every entry).
Exit status 0 when all hold; 1 with what did not (then the scratch tree and
its log are kept, and the log's end printed). The scratch tree is removed at
the end otherwise (--keep keeps it). It copies the working tree, so it also
checks uncommitted work; CI runs it on a clean checkout.
"""
import argparse
import json
import os
import re
import shutil
import subprocess
import sys
import tempfile
import time

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))

HEUN = r'''// Heun's method (the explicit trapezoidal rule): order 2, two right-hand
// sides per step; continuous extension b1(th) = th - th^2/2, b2(th) = th^2/2
// (order 2). Stability polynomial R(z) = 1 + z + z^2/2, real interval 2.
// Written by scripts/check_extension.py into a scratch copy of the tree.
#include <complex>
#include <memory>

#include "integrators/fixed_step.hpp"

namespace pumasim {
namespace {

class ScratchHeun final : public detail::FixedStep {
 public:
  ScratchHeun(const IntegratorOptions& o, double b2, const char* name) : FixedStep(o, 2), b2_(b2), name_(name) {}
  const char* name() const override { return name_; }

 protected:
  void advance_step(double h, bool) override {
    f(t_, x_.data(), k1_.data());
    for (std::size_t i = 0; i < x_.size(); ++i) tmp_[i] = x_[i] + h * k1_[i];
    f(t_ + h, tmp_.data(), k2_.data());
    for (std::size_t i = 0; i < x_.size(); ++i) x_[i] += h * ((1 - b2_) * k1_[i] + b2_ * k2_[i]);
  }
  void extension(double th, double* out) const override {
    for (std::size_t i = 0; i < x_.size(); ++i) out[i] = (th - th * th / 2) * k1_[i] + th * th / 2 * k2_[i];
  }

 private:
  double b2_;
  const char* name_;
};

}  // namespace

namespace detail {
std::unique_ptr<Integrator> make_scratch_heun(const IntegratorOptions& o) {
  return std::make_unique<ScratchHeun>(o, 0.5, "scratch-heun");
}
// b = (0.7, 0.3): consistent but first order.
std::unique_ptr<Integrator> make_scratch_heun_wrong(const IntegratorOptions& o) {
  return std::make_unique<ScratchHeun>(o, 0.3, "scratch-heun-wrong");
}
bool stable_scratch_heun(std::complex<double> z) { return std::abs(1.0 + z + z * z / 2.0) <= 1.0 + 1e-12; }
}  // namespace detail

}  // namespace pumasim
'''

HEUN_DECLARATIONS = '''std::unique_ptr<Integrator> make_scratch_heun(const IntegratorOptions&);
std::unique_ptr<Integrator> make_scratch_heun_wrong(const IntegratorOptions&);
bool stable_scratch_heun(std::complex<double> z);
'''


def heun_row(name, make, stable, real):
    return f'''    {{
        .name = "{name}",
        .summary = "Heun (explicit trapezoidal rule), order 2, fixed step",
        .make = &detail::{make},
        .kind = IntegratorKind::kFixedStep,
        .order = 2,
        .variable_order = false,
        .implicit = false,
        .rhs_per_step = 2,
        .real_stability = {real},
        .stable_at = {stable},
        .dense_order = 2,
        .starter_steps = 0,
        .uses_jacobian = false,
        .exact_jacobian = false,
        .jacobian_choice = false,
        .finds_roots = false,
        .set_valued_friction = false,
    }},
'''


RNEA_HEADER = r'''// A back-end on the paper's probing algorithm under its own name; with
// PUMASIM_SCRATCH_WRONG set in the environment its mass matrix's (0, 0)
// entry is doubled (still symmetric positive definite), which every test of
// H must see. Written by scripts/check_extension.py into a scratch copy of
// the tree.
#pragma once

#include <cstdlib>

#include "models/dynamics/rnea_probing.hpp"

namespace pumasim {

template <class S, int N>
class ScratchRnea : public RneaProbing<S, N> {
 public:
  static constexpr const char* kName = "scratch-rnea";
  explicit ScratchRnea(const Chain<S, N>& chain)
      : RneaProbing<S, N>(chain), wrong_(std::getenv("PUMASIM_SCRATCH_WRONG") != nullptr) {}
  template <class Q, class M>
  void mass_matrix(const Q& q, M&& H) {
    RneaProbing<S, N>::mass_matrix(q, H);
    if (wrong_) H(0, 0) = H(0, 0) + H(0, 0);
  }

 private:
  bool wrong_;
};

}  // namespace pumasim
'''

RNEA_ENTRY = r'''#include "models/dynamics/backend_impl.hpp"
#include "models/dynamics/backends/scratch_rnea.hpp"

namespace pumasim::detail {

BackendInfo scratch_rnea_entry() { return entry<ScratchRnea>("the paper's probing, under another name"); }

}  // namespace pumasim::detail
'''

# Every test source with a registry-parameterised suite (checked: registry_sources_left_out), and the
# back-ends' agreement and identities; the no-allocation guard is its own binary.
TEST_SOURCES = ["test_any_n.cpp", "test_integrators.cpp", "test_conformance.cpp", "test_backends.cpp",
                "test_identities.cpp"]
NO_ALLOC_SOURCES = ["test_no_alloc.cpp"]
# Registry tests a fixed-step method skips, and why.
ALLOWED_SKIPS = {
    "ErrorIsProportionalToTheTolerance": "a fixed-step method has no tolerance",
}
# The other back-ends the chosen suites name (crba, rnea-probing-shared);
# the generated ones are left out of this build, so their own tests are too.
BACKENDS = ["crba", "rnea_probing", "rnea_probing_shared", "scratch_rnea"]
SKIPPED_SUITES = ["GeneratedBackEnds.*"]


def fail(msg):
    print(f"check_extension: {msg}", file=sys.stderr)
    sys.exit(1)


def copy_tree(dst):
    files = subprocess.run(["git", "ls-files", "-z", "--cached", "--others", "--exclude-standard"], cwd=ROOT,
                           check=True, capture_output=True).stdout.decode().split("\0")
    for f in files:
        src = os.path.join(ROOT, f)
        if not f or not os.path.isfile(src):  # deleted in the working tree
            continue
        os.makedirs(os.path.join(dst, os.path.dirname(f)), exist_ok=True)
        shutil.copy2(src, os.path.join(dst, f))


def add_rows(registry_cpp):
    with open(registry_cpp) as fh:
        text = fh.read()
    anchor = "}  // namespace detail\n\nnamespace {\n"
    if text.count(anchor) != 1:
        fail(f"{registry_cpp}: the factory declarations' end ({anchor!r}) is not where expected")
    text = text.replace(anchor, HEUN_DECLARATIONS + anchor)
    table = re.search(r"std::to_array<IntegratorInfo>\(\{\n(.*?)\n\}\);", text, re.S)
    if not table:
        fail(f"{registry_cpp}: no std::to_array<IntegratorInfo> table")
    rows = re.findall(r"    \{\n        \.name = \"([^\"]+)\".*?\n    \},\n", table.group(1) + "\n", re.S)
    body = table.group(1) + "\n"
    # The wrong one claims no region: the stability test, which is not
    # parameterised, would otherwise fail with it in the good run.
    # R(z) = 1 + z + z^2/2: real interval 2; the wrong one's 1 + z + 0.3 z^2: 10/3.
    for name, make, stable, real in [("scratch-heun", "make_scratch_heun", "&detail::stable_scratch_heun", "2.0"),
                                     ("scratch-heun-wrong", "make_scratch_heun_wrong", "nullptr", "10.0 / 3")]:
        later = [r for r in rows if r > name]
        if later:  # before the first row whose name sorts after
            at = body.index(f'    {{\n        .name = "{later[0]}"')
        else:
            at = len(body)
        body = body[:at] + heun_row(name, make, stable, real) + body[at:]
        rows.append(name)
    text = text[:table.start(1)] + body.rstrip("\n") + text[table.end(1):]
    with open(registry_cpp, "w") as fh:
        fh.write(text)


def write(path, text):
    os.makedirs(os.path.dirname(path), exist_ok=True)
    with open(path, "w") as fh:
        fh.write(text)


def run(cmd, cwd, log):
    start = time.time()
    with open(log, "a") as fh:
        fh.write("$ " + " ".join(cmd) + "\n")
        fh.flush()
        r = subprocess.run(cmd, cwd=cwd, stdout=fh, stderr=subprocess.STDOUT)
    print(f"check_extension: {' '.join(cmd[:3])} ... {time.time() - start:.0f} s", file=sys.stderr)
    return r.returncode


def gtest(binary, filt, cwd, env=None):
    return subprocess.run([binary, f"--gtest_filter={filt}", "--gtest_brief=1"], cwd=cwd, capture_output=True,
                          text=True, env={**os.environ, **(env or {})})


def registry_sources_left_out():
    """Test sources with a registry-parameterised suite (INSTANTIATE_TEST_SUITE_P(Registry, ...)) that
    this check does not build: each would fall out of the proof unnoticed."""
    out = []
    for name in sorted(os.listdir(os.path.join(ROOT, "tests"))):
        if name.endswith(".cpp") and name not in TEST_SOURCES + NO_ALLOC_SOURCES:
            with open(os.path.join(ROOT, "tests", name)) as fh:
                if re.search(r"INSTANTIATE_TEST_SUITE_P\(\s*Registry\b", fh.read()):
                    out.append(name)
    return out


def gtest_json(binary, filt, cwd, work, env=None):
    """(exit status, {test name: "RUN" | "SKIPPED" | "FAILED"}) of one gtest run."""
    report = os.path.join(work, "gtest.json")
    r = subprocess.run([binary, f"--gtest_filter={filt}", f"--gtest_output=json:{report}", "--gtest_brief=1"],
                       cwd=cwd, capture_output=True, text=True, env={**os.environ, **(env or {})})
    results = {}
    if os.path.exists(report):
        with open(report) as fh:
            doc = json.load(fh)
        for suite in doc.get("testsuites", []):
            for t in suite.get("testsuite", []):
                state = "FAILED" if t.get("failures") else ("SKIPPED" if t.get("result") == "SKIPPED" else "RUN")
                results[f"{suite['name']}.{t['name']}"] = state
        os.remove(report)
    return r, results


def build(build_dir, target, jobs, tree, log):
    if run(["cmake", "--build", build_dir, "--target", target, "-j", str(jobs)], tree, log) != 0:
        fail_with_log(f"building {target} in the scratch tree failed", log)


def fail_with_log(msg, log):
    tail = ""
    if os.path.exists(log):
        with open(log, errors="replace") as fh:
            tail = "".join(fh.readlines()[-40:])
    fail(f"{msg}; the log's end:\n{tail}")


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--jobs", type=int, default=os.cpu_count() or 2)
    ap.add_argument("--keep", action="store_true", help="keep the scratch tree (its path is printed)")
    args = ap.parse_args()
    left_out = registry_sources_left_out()
    if left_out:
        fail("test sources with a Registry suite that this check does not build (add them to TEST_SOURCES): "
             + ", ".join(left_out))
    tree = tempfile.mkdtemp(prefix="pumasim-extension-")
    log = os.path.join(tree, "check_extension.log")
    try:
        copy_tree(tree)
        # The release preset's settings, folder depth and generator, with the checkout's ccache:
        # what the edit leaves alone is a hit from the checkout's release build.
        build_dir = os.path.join(tree, "build", "release")
        # Configured before the new files exist. This build has a subset of the back-ends
        # (PUMASIM_BACKENDS), which must name the new one once it exists: this subset build's own
        # setting, not an edit of the tree (a full build globs it). That second configure also
        # re-reads the globs, so the globs' CONFIGURE_DEPENDS (what finds new files in an existing
        # build without one) is not what this proves.
        configure = ["cmake", "-S", tree, "-B", build_dir, "-G", "Ninja", "-DCMAKE_BUILD_TYPE=Release",
                     "-DPUMASIM_CCACHE_DIR=" + os.path.join(ROOT, "build", "ccache"), "-DPUMASIM_BUILD_PYTHON=OFF",
                     "-DPUMASIM_BUILD_BENCHMARKS=OFF", "-DPUMASIM_TEST_SOURCES=" + ";".join(TEST_SOURCES)]
        existing = [b for b in BACKENDS if b != "scratch_rnea"]
        if run(configure + ["-DPUMASIM_BACKENDS=" + ";".join(existing)], tree, log) != 0:
            fail_with_log("configuring the scratch tree failed", log)
        write(os.path.join(tree, "integrators/scratch_heun.cpp"), HEUN)
        add_rows(os.path.join(tree, "integrators/registry.cpp"))
        write(os.path.join(tree, "models/dynamics/backends/scratch_rnea.hpp"), RNEA_HEADER)
        write(os.path.join(tree, "models/dynamics/backends/scratch_rnea.cpp"), RNEA_ENTRY)
        if run(["cmake", "-B", build_dir, "-DPUMASIM_BACKENDS=" + ";".join(BACKENDS)], tree, log) != 0:
            fail_with_log("naming the new back-end in the scratch build's subset failed", log)
        build(build_dir, "pumasim_tests", args.jobs, tree, log)
        build(build_dir, "pumasim_no_alloc_tests", args.jobs, tree, log)
        binary = os.path.join(build_dir, "tests", "pumasim_tests")
        listed = subprocess.run([binary, "--gtest_list_tests"], capture_output=True, text=True, check=True).stdout
        suites, suite = {}, None
        for line in listed.splitlines():
            if not line.startswith(" "):
                suite = line.split()[0].rstrip(".")
            elif suite:
                suites.setdefault(suite, []).append(line.split()[0])
        registry_suites = [s for s in suites if s.startswith("Registry/")]
        missing = [s for s in registry_suites if not any(t.endswith("/scratch_heun") for t in suites[s])]
        if not registry_suites or missing:
            fail("registry-parameterised suites without a scratch_heun instance: " + ", ".join(missing or ["(none found)"]))
        good, results = gtest_json(binary, "-*scratch_heun_wrong*:" + ":".join(SKIPPED_SUITES), tree, tree)
        if good.returncode != 0:
            fail("with the new entries, tests fail:\n" + good.stdout[-4000:])
        heun = {t: r for t, r in results.items() if t.endswith("/scratch_heun")}
        unexpected = [t for t, r in heun.items() if r == "SKIPPED" and not any(a in t for a in ALLOWED_SKIPS)]
        if unexpected:
            fail("scratch-heun was skipped where no reason is on record (ALLOWED_SKIPS): " + ", ".join(unexpected))
        no_alloc = subprocess.run([os.path.join(build_dir, "tests", "pumasim_no_alloc_tests"), "--gtest_brief=1"],
                                  cwd=tree, capture_output=True, text=True)
        if no_alloc.returncode != 0:
            fail("with the new back-end, the no-allocation tests fail:\n" + no_alloc.stdout[-4000:])
        wrong, _ = gtest_json(binary, "Registry/Conformance.ConvergesAtItsOrderOnProtheroRobinson/scratch_heun_wrong",
                              tree, tree)
        if wrong.returncode == 0 or "scratch_heun_wrong" not in wrong.stdout:
            fail("the first-order 'scratch-heun-wrong' passed the order test: a new entry can be skipped")
        bad, _ = gtest_json(binary, "BackendAgreement.*", tree, tree, {"PUMASIM_SCRATCH_WRONG": "1"})
        if bad.returncode == 0:
            fail("a back-end with a wrong mass matrix passed BackendAgreement: a new back-end can be skipped")
        ran = sum(r == "RUN" for r in heun.values())
        skipped = sorted(t for t, r in heun.items() if r == "SKIPPED")
        print(f"check_extension: ok: the scratch integrator and back-end, one file and one row each; "
              f"{len(heun)} registry-parameterised tests of scratch-heun: {ran} ran and passed, "
              f"{len(skipped)} skipped for a reason on record ({', '.join(skipped)}); the no-allocation tests "
              f"passed with the new back-end; the wrong integrator and the wrong back-end each failed")
    except SystemExit:
        args.keep = args.keep or os.path.exists(log)  # a failure keeps its tree and log
        raise
    finally:
        if args.keep:
            print(f"check_extension: scratch tree kept at {tree}", file=sys.stderr)
        else:
            shutil.rmtree(tree, ignore_errors=True)


if __name__ == "__main__":
    main()
