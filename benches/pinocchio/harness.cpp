// Pinocchio side of the side-by-side benchmark (benches/pinocchio/run.sh). Not built by cargo
// or CI.
//
//   harness MODEL_BASE [--calls N]
//
// reads MODEL_BASE.pin.txt (a Pinocchio model saved by export_models.py with
// `Model.saveToText`) and MODEL_BASE.pin.state (q, v, tau, RNEA acceleration), then times
// the same four per-call figures as `satsim bench` with the same method (its
// crates/cli/src/commands/bench.rs): for each algorithm a warm-up of N calls, then 7
// repetitions of N calls; each repetition gives the mean time per call and the figure is
// their median. Without --calls, N is calibrated as satsim does (about 1.5 s in all).
// Prints one JSON object of the schema of `satsim bench` (cli-contract.md section 5).
//
// Figures:
//   crba          pinocchio::crba (LOCAL convention, the default; upper triangle only)
//   rnea          pinocchio::rnea(q, v, a)
//   aba           pinocchio::aba(q, v, tau) (LOCAL convention, the default)
//   crba_cholesky nonLinearEffects + crba + cholesky::decompose + cholesky::solve, the work
//                 of satsim's `crba_cholesky` (Pinocchio's Cholesky exploits the tree's
//                 sparsity; satsim's is dense)

#include <pinocchio/algorithm/aba.hpp>
#include <pinocchio/algorithm/cholesky.hpp>
#include <pinocchio/algorithm/crba.hpp>
#include <pinocchio/algorithm/rnea.hpp>
#include <pinocchio/multibody.hpp>
#include <pinocchio/serialization.hpp>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <functional>
#include <iostream>
#include <string>
#include <vector>

namespace {

constexpr int kRepetitions = 7;         // satsim bench's REPETITIONS
constexpr double kTargetSeconds = 1.5;  // satsim bench's TARGET_SECONDS

// The optimiser must assume `p`'s memory is read and written: Rust's `black_box`.
template <typename T>
inline void black_box(T& p) {
  asm volatile("" : : "g"(&p) : "memory");
}

using Clock = std::chrono::steady_clock;

double mean_ns(const std::function<void()>& f, long calls) {
  auto t = Clock::now();
  for (long i = 0; i < calls; ++i) f();
  return std::chrono::duration<double, std::nano>(Clock::now() - t).count() / double(calls);
}

// Mean ns per call of `f`, calling it for about `budget_ms` (satsim bench's `mean_ns`).
double calibrate_ns(const std::function<void()>& f, double budget_ms) {
  auto start = Clock::now();
  long calls = 0;
  while (std::chrono::duration<double, std::milli>(Clock::now() - start).count() < budget_ms) {
    for (int i = 0; i < 64; ++i) f();
    calls += 64;
  }
  return std::chrono::duration<double, std::nano>(Clock::now() - start).count() / double(calls);
}

// The largest of 1, 2, 5 times a power of ten not above n (satsim bench's `round_down`).
long round_down(long n) {
  long p = 1;
  while (p * 10 <= n) p *= 10;
  for (long c : {5 * p, 2 * p, p})
    if (c <= n) return c;
  return 1;
}

Eigen::VectorXd read_vector(std::istream& in, long n) {
  Eigen::VectorXd x(n);
  for (long i = 0; i < n; ++i) in >> x[i];
  return x;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 2) {
    std::fprintf(stderr, "usage: harness MODEL_BASE [--calls N]\n");
    return 2;
  }
  const std::string base = argv[1];
  long calls = 0;
  for (int i = 2; i + 1 < argc; ++i)
    if (std::string(argv[i]) == "--calls") calls = std::atol(argv[i + 1]);

  pinocchio::Model model;
  model.loadFromText(base + ".pin.txt");
  pinocchio::Data data(model);
  std::ifstream st(base + ".pin.state");
  long nq = 0, nv = 0;
  st >> nq >> nv;
  if (!st || nq != model.nq || nv != model.nv) {
    std::fprintf(stderr, "%s.pin.state: bad dimensions\n", base.c_str());
    return 1;
  }
  const Eigen::VectorXd q = read_vector(st, nq), v = read_vector(st, nv),
                        tau = read_vector(st, nv), acc = read_vector(st, nv);
  if (!st) {
    std::fprintf(stderr, "%s.pin.state: truncated\n", base.c_str());
    return 1;
  }

  std::vector<std::pair<const char*, std::function<void()>>> algorithms = {
      {"crba",
       [&] {
         pinocchio::crba(model, data, q);
         black_box(data);
       }},
      {"rnea",
       [&] {
         pinocchio::rnea(model, data, q, v, acc);
         black_box(data);
       }},
      {"aba",
       [&] {
         pinocchio::aba(model, data, q, v, tau);
         black_box(data);
       }},
      {"crba_cholesky",
       [&] {
         pinocchio::nonLinearEffects(model, data, q, v);
         pinocchio::crba(model, data, q);
         pinocchio::cholesky::decompose(model, data);
         data.ddq = tau - data.nle;
         pinocchio::cholesky::solve(model, data, data.ddq);
         black_box(data);
       }},
  };

  if (calls <= 0) {
    double total = 0.0;
    for (auto& a : algorithms) total += calibrate_ns(a.second, 20.0);
    const double per_call_all = total * 1e-9 * (kRepetitions + 1);
    calls = round_down(std::max(100.0, kTargetSeconds / per_call_all));
  }

  std::printf("{\"dof\": %ld, \"calls\": %ld, \"repetitions\": %d, \"ns_per_call\": {", nv,
              calls, kRepetitions);
  for (size_t k = 0; k < algorithms.size(); ++k) {
    auto& f = algorithms[k].second;
    mean_ns(f, calls);  // warm-up
    std::vector<double> means;
    for (int r = 0; r < kRepetitions; ++r) means.push_back(mean_ns(f, calls));
    std::sort(means.begin(), means.end());
    std::printf("%s\"%s\": %.1f", k ? ", " : "", algorithms[k].first, means[kRepetitions / 2]);
  }
  std::printf("}}\n");
  return 0;
}
