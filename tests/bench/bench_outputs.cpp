// Output writing against the whole plan (writing ≤ 5 % of the demo's CPU time).
// Plans the job once through the library as `plan` does (job, cell, part, pipeline::planScan),
// then writes every file `plan` writes (cli::writePlanOutputs, job.yaml, report.json) into a fresh
// folder, best of N in process CPU time (user + system: the kernel's copy into the page cache
// counts), with today's writers and with WriteSettings::reference() (the writers as they were:
// PNG level 6 trying every filter, cairo's PNGs in the SVGs, PLY and npy built in memory first,
// cloud.png's points copied per view), side by side in the same run. Both must give the same
// files apart from the PNG and SVG bytes, whose pixels are compared elsewhere (the tests).
// Usage (from the repository root): build/tests/bench/bench_outputs [runs] [JOB] [today]
// `today`: only today's writers, all of plan's files best of `runs` (for a profiler).
#include <unistd.h>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <string>

#include <scanplan/config/job.h>
#include <scanplan/config/to_problem.h>
#include <scanplan/pipeline/plan_scan.h>
#include "cli/commands/commands.h"
#include "cli/io/output.h"
#include "cli/report/plan_report.h"
#include "cli/report/simulation_files.h"
#include "tests/bench/bench_timing.h"

using namespace scanplan;

namespace {

constexpr double kTargetShare = 0.05;

struct Planned {
  config::JobSpec job;
  pipeline::ScanProblem problem;
  pipeline::ScanPlan plan;
};

// What `plan` does before it writes anything.
Planned planJob(const std::filesystem::path& file) {
  config::JobSpec job = config::loadJob(file);
  kinematics::CellModel cell = config::buildCell(job);
  kinematics::LoadedMesh part = config::loadPart(job, cell);
  pipeline::ScanProblem problem = config::toProblem(job, std::move(cell), std::move(part.mesh));
  pipeline::ScanPlan plan = pipeline::planScan(problem, {});
  return {std::move(job), std::move(problem), std::move(plan)};
}

// Every file `plan` writes for a planned job, into `dir`.
void writeAll(const std::filesystem::path& dir, const Planned& p, const cli::WriteSettings& s) {
  cli::writeFileAtomically(dir / "job.yaml", config::jobToYaml(p.job));
  cli::writePlanOutputs(dir, p.job, p.problem, p.plan, s);
  cli::writeFileAtomically(dir / "report.json",
                           cli::planReportJson(p.job, p.problem.cell, p.plan, p.plan.times));
}

// Best of `runs` of `write` into a new empty folder each time (made and removed untimed), s.
template <class Write>
double bestWrite(int runs, const std::filesystem::path& dir, Write&& write) {
  double best = 1e300;
  for (int r = 0; r < runs; ++r) {
    std::filesystem::remove_all(dir);
    std::filesystem::create_directories(dir);
    const double start = bench::processCpuSeconds();
    write();
    best = std::min(best, bench::processCpuSeconds() - start);
  }
  std::filesystem::remove_all(dir);
  return best;
}

struct Row {
  const char* name;
  double today, reference;
};

}  // namespace

int main(int argc, char** argv) {
  const int runs = argc > 1 ? std::max(1, std::atoi(argv[1])) : 5;
  const std::filesystem::path job = argc > 2 ? argv[2] : "data/jobs/demo_rings.yaml";
  const std::filesystem::path dir =
      std::filesystem::temp_directory_path() / ("bench_outputs-" + std::to_string(::getpid()));

  const double start = bench::processCpuSeconds();
  const Planned p = planJob(job);
  const double planning = bench::processCpuSeconds() - start;
  if (!p.plan.planned() || !p.plan.simulation) {
    std::fprintf(stderr, "%s: not planned, or without the simulation: nothing to measure\n",
                 job.string().c_str());
    return 1;
  }
  const cli::WriteSettings today, reference = cli::WriteSettings::reference();
  if (argc > 3 && std::string(argv[3]) == "today") {
    std::printf("all of plan's files, today's writers, best of %d: %.4f s\n", runs,
                bestWrite(runs, dir, [&] { writeAll(dir, p, today); }));
    return 0;
  }
  const auto time = [&](const cli::WriteSettings& s, auto&& part) {
    return bestWrite(runs, dir, [&] { part(s); });
  };
  const auto both = [&](const char* name, auto&& part) {
    return Row{name, time(today, part), time(reference, part)};
  };
  const Row rows[] = {
      both("path.csv, path.png",
           [&](const cli::WriteSettings& s) {
             cli::writePathOutputs(dir, p.problem.cell, p.problem.part, p.plan.prepared->path.path,
                                   s);
           }),
      both("configmap npy, json, figures",
           [&](const cli::WriteSettings& s) {
             cli::writeMapOutputs(dir, p.job, p.plan.prepared->map, s);
           }),
      both("cloud.ply, coverage.ply, cloud.png",
           [&](const cli::WriteSettings& s) {
             cli::writeSimulationOutputs(dir, p.job, p.problem.part, *p.plan.simulation, s);
           }),
      both("all of plan's files", [&](const cli::WriteSettings& s) { writeAll(dir, p, s); }),
  };
  const Row& all = rows[3];

  std::printf("job %s, best of %d, process CPU time (user + system)\n", job.string().c_str(), runs);
  std::printf("planning (load, path, maps, plan, trajectory, validation, simulation): %.3f s\n",
              planning);
  std::printf("%-36s %10s %10s %8s\n", "writing", "today s", "ref. s", "ratio");
  for (const Row& r : rows) {
    std::printf("%-36s %10.4f %10.4f %7.2fx\n", r.name, r.today, r.reference,
                r.reference / r.today);
  }
  // What the groups leave out: trajectory.csv, programs/, configmap_path.png/.svg, replay.html,
  // cell.png, report.json, job.yaml (the best runs of different sets: an estimate).
  const double rest_today = all.today - rows[0].today - rows[1].today - rows[2].today;
  const double rest_reference =
      all.reference - rows[0].reference - rows[1].reference - rows[2].reference;
  std::printf("%-36s %10.4f %10.4f %7.2fx\n", "the rest (all minus the groups)", rest_today,
              rest_reference, rest_reference / rest_today);
  const double plan_today = planning + all.today, plan_reference = planning + all.reference;
  std::printf("whole plan, CPU: %.3f s today, %.3f s with the reference writers\n", plan_today,
              plan_reference);
  const double share = all.today / plan_today;
  std::printf("writing share: %.1f %% today (target <= %.0f %%: %s), %.1f %% with the reference\n",
              100.0 * share, 100.0 * kTargetShare, share <= kTargetShare ? "met" : "NOT met",
              100.0 * all.reference / plan_reference);
  std::printf("writing, today / reference: %.2f (%.2fx faster)\n", all.today / all.reference,
              all.reference / all.today);
  return 0;
}
