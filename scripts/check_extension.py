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
with no other edit. It then configures and builds the suites that iterate
the registries (integrators, conformance, back-ends, identities) and checks
that
  1. the new entries take part: every registry-parameterised suite has a
     scratch_heun instance, and every one of them passes; the registry's
     tests pass with the new back-end among the built ones;
  2. no test skips them silently: the wrong-weights integrator fails its
     order test, and the back-end made wrong (PUMASIM_SCRATCH_WRONG: its mass
     matrix's first entry doubled) fails the back-end agreement.
Exit status 0 when all hold; 1 with what did not. The scratch tree is removed
at the end (--keep keeps it).
"""
import argparse
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


def heun_row(name, make, stable):
    return f'''    {{
        .name = "{name}",
        .summary = "Heun (explicit trapezoidal rule), order 2, fixed step",
        .make = &detail::{make},
        .kind = IntegratorKind::kFixedStep,
        .order = 2,
        .variable_order = false,
        .implicit = false,
        .rhs_per_step = 2,
        .real_stability = 2.0,
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

TEST_SOURCES = ["test_integrators.cpp", "test_conformance.cpp", "test_backends.cpp", "test_identities.cpp"]
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
    for name, make, stable in [("scratch-heun", "make_scratch_heun", "&detail::stable_scratch_heun"),
                               ("scratch-heun-wrong", "make_scratch_heun_wrong", "nullptr")]:
        later = [r for r in rows if r > name]
        if later:  # before the first row whose name sorts after
            at = body.index(f'    {{\n        .name = "{later[0]}"')
        else:
            at = len(body)
        body = body[:at] + heun_row(name, make, stable) + body[at:]
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


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--jobs", type=int, default=os.cpu_count() or 2)
    ap.add_argument("--keep", action="store_true", help="keep the scratch tree (its path is printed)")
    args = ap.parse_args()
    tree = tempfile.mkdtemp(prefix="pumasim-extension-")
    log = os.path.join(tree, "check_extension.log")
    try:
        copy_tree(tree)
        write(os.path.join(tree, "integrators/scratch_heun.cpp"), HEUN)
        add_rows(os.path.join(tree, "integrators/registry.cpp"))
        hpp = os.path.join(tree, "models/dynamics/backends/scratch_rnea.hpp")
        write(hpp, RNEA_HEADER)
        write(os.path.join(tree, "models/dynamics/backends/scratch_rnea.cpp"), RNEA_ENTRY)
        build = os.path.join(tree, "build")
        configure = ["cmake", "-S", tree, "-B", build, "-DCMAKE_BUILD_TYPE=RelWithDebInfo",
                     "-DCMAKE_CXX_FLAGS_RELWITHDEBINFO=-O1", "-DPUMASIM_NATIVE=OFF", "-DPUMASIM_BUILD_PYTHON=OFF",
                     "-DPUMASIM_BUILD_BENCHMARKS=OFF", "-DPUMASIM_BACKENDS=" + ";".join(BACKENDS),
                     "-DPUMASIM_TEST_SOURCES=" + ";".join(TEST_SOURCES)]
        if run(configure, tree, log) != 0:
            fail(f"configuring the scratch tree failed (log: {log})")
        if run(["cmake", "--build", build, "--target", "pumasim_tests", "-j", str(args.jobs)], tree, log) != 0:
            fail(f"building the scratch tree failed (log: {log})")
        binary = os.path.join(build, "tests", "pumasim_tests")
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
        good = gtest(binary, "-*scratch_heun_wrong*:" + ":".join(SKIPPED_SUITES), tree)
        if good.returncode != 0:
            fail("with the new entries, tests fail:\n" + good.stdout[-4000:])
        wrong = gtest(binary, "Registry/Conformance.ConvergesAtItsOrderOnProtheroRobinson/scratch_heun_wrong", tree)
        if wrong.returncode == 0 or "scratch_heun_wrong" not in wrong.stdout:
            fail("the first-order 'scratch-heun-wrong' passed the order test: a new entry can be skipped")
        bad = gtest(binary, "BackendAgreement.*", tree, {"PUMASIM_SCRATCH_WRONG": "1"})
        if bad.returncode == 0:
            fail("a back-end with a wrong mass matrix passed BackendAgreement: a new back-end can be skipped")
        n_scratch = sum(t.endswith("/scratch_heun") for s in registry_suites for t in suites[s])
        print(f"check_extension: ok: the scratch integrator and back-end built with one file and one row each; "
              f"{n_scratch} registry-parameterised tests ran scratch-heun and passed; the wrong integrator and "
              f"the wrong back-end each failed")
    finally:
        if args.keep:
            print(f"check_extension: scratch tree kept at {tree}", file=sys.stderr)
        else:
            shutil.rmtree(tree, ignore_errors=True)


if __name__ == "__main__":
    main()
