// `granagg analyze`: bad inputs (exit 2 with a message naming the option or file), malformed
// trajectories (exit 1 naming file and frame, --allow-partial), and an end-to-end ensemble run on
// trajectories made by `granagg md`.
#include <catch2/catch.hpp>

#include "RunCommand.h"

#include <unistd.h>
#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <string>

#include "common/Csv.h"
#include "common/Hdf5.h"

#include "TestUtil.h"

using granagg::test::tempDir;

namespace fs = std::filesystem;

namespace {
/// A small `granagg md` run (300 particles to t = 1); returns its folder.
fs::path mdRun(const fs::path& dir, const std::string& name, int seed) {
  const fs::path cfg = dir / (name + ".toml");
  std::ofstream(cfg) << "[input]\nversion = 1\n[system]\nN = 300\nseed = " << seed
                     << "\n[run]\nt_end = 1.0\n[output]\nframes_per_decade = 10\n";
  const fs::path out = dir / name;
  const Run r =
      runGranagg("md --config " + cfg.string() + " --out " + out.string() + " -q --threads 1");
  INFO(r.output);
  REQUIRE(r.status == 0);
  return out;
}

/// A 2-frame LAMMPS dump of 3 atoms, optionally cut inside the second frame.
std::string tinyDump(const fs::path& dir, bool cut) {
  const fs::path p = dir / (cut ? "cut.dump" : "ok.dump");
  std::ofstream out(p);
  for (int k = 0; k < 2; ++k) {
    out << "ITEM: TIMESTEP\n"
        << 10 * k << "\nITEM: NUMBER OF ATOMS\n3\nITEM: BOX BOUNDS pp pp pp\n0 6\n0 6\n0 6\n"
        << "ITEM: ATOMS id x y z ix iy iz vx vy vz q\n";
    out << "1 1 1 1 0 0 0 0.1 0 0 0.01\n";
    if (cut && k == 1) break;
    out << "2 2 1 1 0 0 0 -0.1 0 0 -0.01\n3 4 4 4 0 0 0 0 0.2 0 0\n";
  }
  return p.string();
}
}  // namespace

TEST_CASE("analyze rejects bad input with exit status 2 and a message naming it",
          "[cli][analyze]") {
  const fs::path dir = tempDir("bad");
  const std::string dump = tinyDump(dir, false);
  const std::string out = " --out " + (dir / "o").string();
  struct Case {
    std::string args, says;
  };
  for (const Case& c : {Case{"analyze" + out, "runs"},
                        Case{"analyze " + (dir / "nosuch.h5").string() + out, "nosuch.h5"},
                        Case{"analyze " + dump + out + " --grid-spacing -1", "--grid-spacing"},
                        Case{"analyze " + dump + out + " --grid-spacing 0", "--grid-spacing"},
                        Case{"analyze " + dump + out + " --grid-min-fill 2", "--grid-min-fill"},
                        Case{"analyze " + dump + out + " --tolerance -0.5", "--tolerance"},
                        Case{"analyze " + dump + out + " --threads 0", "--threads"},
                        Case{"analyze " + dump + out + " --msd-origins sometimes", "--msd-origins"},
                        Case{"analyze " + dump + out + " --fit-window 5 1", "--fit-window"},
                        Case{"analyze " + dump + out + " --slope-ratio 1", "--slope-ratio"},
                        Case{"analyze " + dump + out + " --grid-assign spline", "--grid-assign"},
                        Case{"analyze " + dump + out + " --no-grid --no-particle", "--no-grid"},
                        Case{"analyze " + dump + out + " --kappa -1", "--kappa"},
                        Case{"analyze " + (dir / "empty").string() + out, "traj.h5"}}) {
    fs::create_directories(dir / "empty");
    INFO(c.args);
    const Run r = runGranagg(c.args + " -q");
    CHECK(r.status == 2);
    CHECK_THAT(r.output, Catch::Contains(c.says));
  }
  fs::remove_all(dir);
}

TEST_CASE(
    "analyze of a truncated dump fails naming file and frame, --allow-partial analyses the rest",
    "[cli][analyze]") {
  const fs::path dir = tempDir("cut");
  const std::string dump = tinyDump(dir, true);
  const Run r = runGranagg("analyze " + dump + " --out " + (dir / "o1").string() + " -q");
  CHECK(r.status == 1);
  CHECK_THAT(r.output, Catch::Contains("cut.dump") && Catch::Contains("frame 1"));
  CHECK_FALSE(fs::exists(dir / "o1"));  // nothing left behind that would block the rerun
  const Run p =
      runGranagg("analyze " + dump + " --out " + (dir / "o2").string() + " --allow-partial");
  INFO(p.output);
  CHECK(p.status == 0);
  CHECK_THAT(p.output, Catch::Contains("PARTIAL"));
  CHECK(fs::exists(dir / "o2" / "S_t.csv"));
  // a truncated HDF5 file cannot be opened at all
  const fs::path run = mdRun(dir, "run", 3);
  const fs::path cut = dir / "cut.h5";
  fs::copy_file(run / "traj.h5", cut);
  fs::resize_file(cut, fs::file_size(cut) / 2);
  const Run h = runGranagg("analyze " + cut.string() + " --out " + (dir / "o3").string() +
                           " -q --allow-partial");
  CHECK(h.status == 1);
  CHECK_THAT(h.output, Catch::Contains("cut.h5") && Catch::Contains("frame 0"));
  CHECK_FALSE(fs::exists(dir / "o3"));
  // one run given twice is not an ensemble of two
  const Run twice = runGranagg("analyze " + run.string() + " " + run.string() + "/ --out " +
                               (dir / "o4").string() + " -q");
  CHECK(twice.status == 2);
  CHECK_THAT(twice.output, Catch::Contains("given twice"));
  // runs of different systems (N = 300 and a 3-atom dump) are not one ensemble
  const std::string other = tinyDump(dir, false);
  const Run mixed = runGranagg("analyze " + run.string() + " " + other + " --out " +
                               (dir / "o5").string() + " -q");
  CHECK(mixed.status == 2);
  CHECK_THAT(mixed.output, Catch::Contains("(N = 300)") && Catch::Contains("(N = 3)") &&
                               Catch::Contains("different systems"));
  CHECK_FALSE(fs::exists(dir / "o5"));
  fs::remove_all(dir);
}

TEST_CASE("analyze of an md ensemble writes ensemble and per-run tables and analysis.h5",
          "[cli][analyze]") {
  const fs::path dir = tempDir("ens");
  const fs::path a = mdRun(dir, "a", 1), b = mdRun(dir, "b", 2);
  const fs::path out = dir / "out";
  const std::string cmd = "analyze " + a.string() + " " + (b / "traj.h5").string() + " --out " +
                          out.string() + " --write-grid --bootstrap 100 --threads 1";
  const Run r = runGranagg(cmd);
  INFO(r.output);
  REQUIRE(r.status == 0);
  CHECK_THAT(r.output, Catch::Contains("z (grid)") && Catch::Contains("bootstrap"));
  for (const char* f :
       {"S_t.csv", "N_s_grid.csv", "N_s_particle.csv", "fisher.csv", "fisher_pooled.csv",
        "thermo.csv", "msd.csv", "speed_dist.csv", "nstick.csv", "fits.csv", "analysis.h5",
        "per_run/S_t.csv", "per_run/charge_speed.csv", "per_run/fits.csv"}) {
    INFO(f);
    CHECK(fs::exists(out / f));
  }
  const auto S = granagg::common::readCsv((out / "S_t.csv").string());
  const auto per_run = granagg::common::readCsv((out / "per_run" / "S_t.csv").string());
  for (const char* c : {"t", "S_grid_mean", "S_grid_se", "S_particle_mean", "S_particle_se",
                        "n_runs", "z_local_particle_of_mean"})
    CHECK_NOTHROW(S.column(c));
  CHECK(per_run.rows.size() == 2 * S.rows.size());  // same frame times in both runs
  CHECK(per_run.columns.front() == "run");
  bool has_run1 = false;
  for (const auto& m : S.meta) has_run1 |= m.first == "run.1";
  CHECK(has_run1);
  // the homogeneous gas right after the start: every particle cluster is small
  CHECK(S.rows.front()[S.column("S_particle_mean")] < 3.0);
  const auto fits = granagg::common::readCsv((out / "fits.csv").string());
  REQUIRE(fits.rows.size() == 1);
  CHECK(fits.rows[0][fits.column("runs")] == 2.0);

  // refuses to overwrite without --force
  const Run again = runGranagg(cmd + " -q");
  CHECK(again.status == 2);
  CHECK_THAT(again.output, Catch::Contains("--force"));
  CHECK(runGranagg(cmd + " -q --force").status == 0);

  if (sh("/usr/bin/python3 -c 'import h5py'").status == 0) {
    const Run py =
        sh("/usr/bin/python3 -c \"import h5py; f = h5py.File('" + (out / "analysis.h5").string() +
           "'); g = f['runs/0/grid']; n = g.attrs['cells_per_side']; "
           "assert g['labels'].shape[1:] == (n, n, n), g['labels'].shape; "
           "assert g['labels'].shape[0] == len(f['runs/0/S_t/t']); "
           "assert 'S_grid_mean' in f['ensemble/S_t']; print('ok')\"");
    INFO(py.output);
    CHECK(py.status == 0);
  } else {
    WARN("h5py not available: analysis.h5 layout not checked from Python");
  }
  fs::remove_all(dir);
}

TEST_CASE("analyze warns when the growth-exponent window holds too few frames",
          "[cli][analyze]") {
  // The run's frames lie in t = 0 .. 1; a window over [100, 200] holds none, so z is NaN: said on
  // stderr, with the tables written and exit status 0.
  const fs::path dir = tempDir("window");
  const fs::path run = mdRun(dir, "run", 4);
  const Run r = runGranagg("analyze " + run.string() + " --out " + (dir / "o").string() +
                           " --fit-window 100 200 -q");
  INFO(r.output);
  CHECK(r.status == 0);  // the tables are still written: a warning, not an error
  CHECK_THAT(r.output, Catch::Contains("analyze: warning: --fit-window [100, 200] holds 0 frames"));
  CHECK_THAT(r.output, Catch::Contains("the frames span t = 0 .. 0.99"));
  const auto fits = granagg::common::readCsv((dir / "o" / "fits.csv").string());
  REQUIRE(fits.rows.size() == 1);
  CHECK(std::isnan(fits.rows[0][fits.column("z_particle")]));
  // a window holding frames, and the default window (the last decade): no such warning
  for (const std::string window : {" --fit-window 0.1 1", ""}) {
    const Run ok = runGranagg("analyze " + run.string() + " --out " + (dir / "o2").string() +
                              window + " -q --force");
    INFO(ok.output);
    CHECK(ok.status == 0);
    CHECK_THAT(ok.output, !Catch::Contains("holds"));
  }
  // a dump of two frames (t = 0 and 10) cannot hold 3 in its last decade: said, not hidden
  const Run two = runGranagg("analyze " + tinyDump(dir, false) + " --out " +
                             (dir / "o3").string() + " -q");
  CHECK(two.status == 0);
  CHECK_THAT(two.output, Catch::Contains("the growth-exponent window (the last decade) [1, 10] "
                                         "holds 1 frame"));
  fs::remove_all(dir);
}

TEST_CASE("analyze reports no growth exponent where S does not change", "[cli][analyze]") {
  // Four frames of one configuration: four touching particles fill one grid cell (local filling
  // fraction 4 (pi/6) / 8 = 0.26 >= 0.25) and form one particle cluster, so S_grid and
  // S_particle are the same at every frame: no exponent, not z = 0 [0, 0].
  const fs::path dir = tempDir("flat");
  const fs::path dump = dir / "still.dump";
  {
    std::ofstream out(dump);
    for (int k = 1; k <= 4; ++k)
      out << "ITEM: TIMESTEP\n"
          << k << "\nITEM: NUMBER OF ATOMS\n4\nITEM: BOX BOUNDS pp pp pp\n0 6\n0 6\n0 6\n"
          << "ITEM: ATOMS id x y z\n"
          << "1 0.5 0.5 0.5\n2 1.5 0.5 0.5\n3 0.5 1.5 0.5\n4 0.5 0.5 1.5\n";
  }
  const Run r = runGranagg("analyze " + dump.string() + " --out " + (dir / "o").string());
  INFO(r.output);
  CHECK(r.status == 0);
  CHECK_THAT(r.output, Catch::Contains("z (grid) = n/a, z (particle) = n/a"));
  CHECK_THAT(r.output, Catch::Contains("analyze: warning: S_grid_mean is 1 at every frame of the "
                                       "growth-exponent window (the last decade) [0.4, 4]"));
  CHECK_THAT(r.output, Catch::Contains("analyze: warning: S_particle_mean is 4 at every frame"));
  const auto fits = granagg::common::readCsv((dir / "o" / "fits.csv").string());
  REQUIRE(fits.rows.size() == 1);
  for (const char* c : {"z_grid", "z_grid_low", "z_grid_high", "z_particle", "z_particle_low"})
    CHECK(std::isnan(fits.rows[0][fits.column(c)]));
  fs::remove_all(dir);
}

TEST_CASE("analyze says when a trajectory ends before its run.t_end", "[cli][analyze]") {
  // A finished run of t_end = 1, then the same file with /parameters saying run.t_end = 2: what an
  // interrupted run looks like (its frames stop before the configured end).
  const fs::path dir = tempDir("unfinished");
  const fs::path run = mdRun(dir, "run", 5);
  const Run done = runGranagg("analyze " + run.string() + " --out " + (dir / "o1").string() +
                              " -q");
  INFO(done.output);
  CHECK(done.status == 0);
  CHECK_THAT(done.output, !Catch::Contains("run.t_end"));

  const fs::path cut = dir / "cut";
  fs::create_directories(cut);
  fs::copy_file(run / "traj.h5", cut / "traj.h5");
  {
    namespace h5 = granagg::common::h5;
    h5::Handle file(H5Fopen((cut / "traj.h5").c_str(), H5F_ACC_RDWR, H5P_DEFAULT));
    REQUIRE(file.valid());
    h5::Handle par(H5Gopen2(file.get(), "parameters", H5P_DEFAULT));
    REQUIRE(par.valid());
    REQUIRE(H5Adelete(par.get(), "run.t_end") >= 0);
    h5::writeAttribute(par.get(), "run.t_end", 2.0, "test");
  }
  const Run r = runGranagg("analyze " + cut.string() + " --out " + (dir / "o2").string() + " -q");
  INFO(r.output);
  CHECK(r.status == 0);
  CHECK_THAT(r.output,
             Catch::Contains("analyze: warning: run 0 (" + cut.string() + ") ends at t = "));
  CHECK_THAT(r.output, Catch::Contains("before its run.t_end = 2: an unfinished run"));
  fs::remove_all(dir);
}

TEST_CASE("analyze on a full disk: one line naming the file, exit 1, no folder left behind",
          "[cli][analyze][faults]") {
  const fs::path dir = tempDir("fulldisk");
  const fs::path run = mdRun(dir, "run", 5);
  // the size of a complete analysis, to place the limits inside it
  const Run ok = runGranagg("analyze " + run.string() + " --out " + (dir / "ok").string() + " -q");
  REQUIRE(ok.status == 0);
  const auto h5 = fs::file_size(dir / "ok" / "analysis.h5");
  // A file-size limit (ulimit -f, in kB) fails each write past it with EFBIG, as a full disk
  // fails it with ENOSPC: first on a CSV table (4 kB), then inside analysis.h5 (h5/2).
  for (const std::uintmax_t kb : {std::uintmax_t{4}, h5 / 2048}) {
    INFO("limit " << kb << " kB, analysis.h5 " << h5 << " bytes");
    const fs::path out = dir / ("full" + std::to_string(kb));
    const Run r = sh("ulimit -f " + std::to_string(kb) + " && " + GRANAGG_BINARY + " analyze " +
                     run.string() + " --out " + out.string() + " -q");
    CHECK(r.status == 1);  // not 153 (SIGXFSZ) nor 139 (HDF5 at exit after a failed close)
    CHECK_THAT(r.output, Catch::Contains("the file-size limit is reached") &&
                             Catch::Contains(out.string()));
    CHECK(std::count(r.output.begin(), r.output.end(), '\n') == 1);
    CHECK_FALSE(fs::exists(out));  // no table, no analysis.h5, no lock that would pass for done
  }
  // a full disk inside analysis.h5 (the fault hook of common/FaultInjection.h: the 20th write
  // through the journaled driver and all later ones report ENOSPC)
  const fs::path out = dir / "enospc";
  const Run e = sh("GRANAGG_FAULT=enospc:h5write:20 " + std::string(GRANAGG_BINARY) +
                   " analyze " + run.string() + " --out " + out.string() + " -q");
  CHECK(e.status == 1);
  CHECK_THAT(e.output, Catch::Contains("analysis.h5") && Catch::Contains("the disk is full"));
  CHECK_FALSE(fs::exists(out));
  fs::remove_all(dir);
}
