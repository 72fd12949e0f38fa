#include "md/run/OutputReporters.h"

#include <algorithm>
#include <cctype>
#include <stdexcept>

#include "common/Csv.h"
#include "common/H5mdReader.h"
#include "common/Version.h"
#include "md/config/ConfigParser.h"
#include "md/run/Simulation.h"

namespace granagg::md {
namespace fs = std::filesystem;

namespace {

/// The observables as /granagg/observables stores them (docs/model.md section 10).
std::vector<std::pair<std::string, double>> observableRow(const Observables& o, double dt) {
  return {{"temperature", o.temperature},
          {"kinetic_energy", o.kinetic_energy},
          {"elastic_energy", o.elastic_energy},
          {"momentum_x", o.momentum[0]},
          {"momentum_y", o.momentum[1]},
          {"momentum_z", o.momentum[2]},
          {"contacts_per_particle", o.contacts_per_particle},
          {"collisions", static_cast<double>(o.collisions)},
          {"mean_overlap", o.mean_overlap},
          {"total_charge", o.total_charge},
          {"mean_abs_charge", o.mean_abs_charge},
          {"max_abs_charge", o.max_abs_charge},
          {"coulomb_energy", o.coulomb_energy},
          {"max_overlap", o.max_overlap},
          {"dt", dt}};
}

/// The frame to write: the physical state, with its per-particle forces when output.write_forces
/// (collective; empty on ranks that do not write).
Frame outputFrame(const RunEngine& engine, const MdConfig& cfg) {
  Frame f = engine.frame(StateKind::Physical);
  // (empty on a rank that does not write)
  if (cfg.output.write_forces) f.force = engine.forces(StateKind::Physical);
  return f;
}

}  // namespace

std::vector<std::pair<std::string, std::string>> trajectoryParameters(
    const MdConfig& cfg, const RunEngine& engine, const std::string& command_line,
    const std::string& dt_reason) {
  auto params = flatten(cfg);
  params.emplace_back("version", common::versionString());
  params.emplace_back("command", command_line);
  params.emplace_back("backend", engine.description());
  for (auto& p : engine.parameters()) params.push_back(std::move(p));
  params.emplace_back("dt", common::formatReal(engine.dt()));
  params.emplace_back("dt_reason", dt_reason);
  if (const CoulombSetup* cs = engine.coulombSetup()) {  // chosen for coulomb.accuracy
    params.emplace_back("coulomb_alpha", common::formatReal(cs->alpha));
    params.emplace_back("coulomb_r_cut_used", common::formatReal(cs->r_cut));
    params.emplace_back("coulomb_mesh_used", std::to_string(cs->mesh));
    params.emplace_back("coulomb_order_used", std::to_string(cs->order));
    params.emplace_back("coulomb_k_max", std::to_string(cs->k_max));
    params.emplace_back("coulomb_estimated_error", common::formatReal(cs->estimated_error));
    params.emplace_back("coulomb_sum_q2_design", common::formatReal(cs->sum_q2_design));
    params.emplace_back("coulomb_r_fast_used", common::formatReal(cs->r_fast));
    params.emplace_back("coulomb_every_used", std::to_string(cs->every));
    params.emplace_back("coulomb_every_max_used", std::to_string(cs->every_max));
  }
  return params;
}

// ---- TrajectoryReporter ------------------------------------------------------------------------

TrajectoryReporter::TrajectoryReporter(RunEngine& engine, const MdConfig& cfg, fs::path file,
                                       std::vector<std::int64_t> frame_steps,
                                       std::size_t next_frame, std::size_t frames_written,
                                       std::int64_t last_step)
    : m_engine(engine),
      m_cfg(cfg),
      m_file(std::move(file)),
      m_frame_steps(std::move(frame_steps)),
      m_next_frame(next_frame),
      m_frames_written(frames_written),
      m_last_step(last_step) {}

void TrajectoryReporter::create(const std::vector<std::pair<std::string, std::string>>& params,
                                const std::string& config_toml, bool overwrite,
                                const Observables& o) {
  // (collective; not needed when no frame is stored)
  const Frame f = m_cfg.output.trajectory ? outputFrame(m_engine, m_cfg) : Frame{};
  if (m_engine.writesFiles()) {
    m_writer = std::make_unique<H5mdWriter>(m_file.string(), m_engine.size(), params, config_toml,
                                            overwrite, m_cfg.output.write_velocities,
                                            m_cfg.output.write_forces);
    m_writer->writeObservables(o.step, o.time, observableRow(o, m_engine.dt()));
    if (m_cfg.output.trajectory) m_writer->writeFrame(f);
    watch();
  }
  m_frames_written = m_cfg.output.trajectory ? 1 : 0;
  m_frame_step = m_engine.step();
  // the schedule's frames up to this step are this one
  m_next_frame = static_cast<std::size_t>(
      std::upper_bound(m_frame_steps.begin(), m_frame_steps.end(), m_engine.step()) -
      m_frame_steps.begin());
}

void TrajectoryReporter::reopen(double t_end, const std::string& command_line,
                                const std::string& version) {
  if (!m_engine.writesFiles()) return;
  m_writer = std::make_unique<H5mdWriter>(
      H5mdWriter::reopen(m_file.string(), m_engine.size(), m_engine.step(),
                         m_cfg.output.write_velocities, m_cfg.output.write_forces));
  m_repair_note = m_writer->repairNote();
  m_writer->recordRestart(m_engine.step(), m_engine.time(), t_end, command_line, version);
  watch();
}

void TrajectoryReporter::addFrameStep(std::int64_t step) {
  if (!m_frame_steps.empty() && step <= m_frame_steps.back())
    throw std::logic_error("TrajectoryReporter::addFrameStep: frame steps must increase");
  m_frame_steps.push_back(step);
}

std::int64_t TrajectoryReporter::nextStep(const Simulation&) const {
  const std::int64_t every = m_cfg.output.observable_interval;
  std::int64_t next = (m_engine.step() / every + 1) * every;
  if (m_next_frame < m_frame_steps.size()) next = std::min(next, m_frame_steps[m_next_frame]);
  return next;
}

bool TrajectoryReporter::needsObservables(const Simulation&) const {
  const std::int64_t step = m_engine.step();
  return step % m_cfg.output.observable_interval == 0 || step == m_last_step;
}

void TrajectoryReporter::report(const Simulation& sim) {
  if (m_writer) check();
  const std::int64_t step = m_engine.step();
  const Observables& o = sim.lastObservables();
  if (m_writer && (step % m_cfg.output.observable_interval == 0 || step == m_last_step))
    m_writer->writeObservables(o.step, o.time, observableRow(o, m_engine.dt()));
  if (m_next_frame < m_frame_steps.size() && step == m_frame_steps[m_next_frame]) {
    writeFrame();
    ++m_next_frame;
  }
}

void TrajectoryReporter::writeFrame() {
  m_frame_step = m_engine.step();
  if (!m_cfg.output.trajectory) return;  // a frame time without a stored frame
  const Frame f = outputFrame(m_engine, m_cfg);  // (collective)
  if (m_writer) m_writer->writeFrame(f);
  ++m_frames_written;
}

std::size_t TrajectoryReporter::framesWritten() const {
  return m_writer ? m_writer->frames() : m_frames_written;
}

void TrajectoryReporter::flush() {
  if (m_writer) m_writer->flush();
}

void TrajectoryReporter::checkpointWritten(fs::path file, std::int64_t step) {
  m_checkpoint_file = std::move(file);
  m_checkpoint_step = step;
}

void TrajectoryReporter::damaged(const std::string& what) const {
  throw std::runtime_error(
      m_file.string() + " was damaged while this run wrote it (" + what +
      "); its frames cannot be trusted. Start the run again into a new folder" +
      (m_checkpoint_step >= 0
           ? " (" + m_checkpoint_file.filename().string() + " holds step " +
                 std::to_string(m_checkpoint_step) + ", but the trajectory up to it is lost)"
           : ""));
}

void TrajectoryReporter::watch() {
  if (::stat(m_file.c_str(), &m_stat) != 0) damaged("it is gone");
}

void TrajectoryReporter::check() {
  if (!m_writer) return;
  // the file must be the one this run opened, and no shorter (the HDF5 library only ever
  // extends a file it writes)
  struct stat now {};
  if (::stat(m_file.c_str(), &now) != 0) damaged("it was removed");
  if (now.st_ino != m_stat.st_ino || now.st_dev != m_stat.st_dev)
    damaged("another file took its name");
  if (now.st_size < m_stat.st_size)
    damaged("its size fell from " + std::to_string(m_stat.st_size) + " to " +
            std::to_string(now.st_size) + " bytes");
  m_stat = now;
}

void TrajectoryReporter::close(bool verify) {
  if (!m_writer) return;
  m_writer->close();
  const std::size_t written = m_writer->frames();
  if (!verify) return;
  // after closing: it reads back whole, with every frame written
  try {
    const common::H5mdReader reader(m_file.string());
    if (reader.frames() != written)
      damaged("it reads back with " + std::to_string(reader.frames()) + " frames of the " +
              std::to_string(written) + " written");
    if (written > 0) {
      reader.readFrame(0);
      reader.readFrame(written - 1);
    }
  } catch (const std::runtime_error& e) {
    if (std::string(e.what()).find("was damaged while") != std::string::npos) throw;
    damaged(std::string("it cannot be read back: ") + e.what());
  }
}

// ---- CheckpointReporter ------------------------------------------------------------------------

CheckpointReporter::CheckpointReporter(RunEngine& engine, const MdConfig& cfg, fs::path folder,
                                       TrajectoryReporter& trajectory, std::int64_t last_step)
    : m_engine(engine),
      m_cfg(cfg),
      m_folder(std::move(folder)),
      m_trajectory(trajectory),
      m_last_step(last_step) {
  if (last_step >= 0) m_trajectory.checkpointWritten(m_engine.checkpointPath(m_folder), last_step);
}

std::int64_t CheckpointReporter::nextStep(const Simulation& sim) const {
  const std::int64_t every = m_cfg.output.checkpoint_interval;
  return every > 0 ? (m_engine.step() / every + 1) * every : Reporter::nextStep(sim);
}

void CheckpointReporter::report(const Simulation&) {
  const std::int64_t every = m_cfg.output.checkpoint_interval;
  const bool by_steps = every > 0 && m_engine.step() % every == 0;
  // (the ranks' clocks may disagree: the wall-time checkpoint is agreed on)
  const bool by_wall =
      m_cfg.output.checkpoint_wall_seconds > 0 &&
      m_engine.anyRank(std::chrono::duration<double>(Clock::now() - m_last_time).count() >
                       m_cfg.output.checkpoint_wall_seconds);
  if (by_steps || by_wall) save();
}

void CheckpointReporter::save() {
  if (m_before) m_before(m_engine.step());
  m_trajectory.flush();
  RunFields run;
  run.config_toml = toToml(m_cfg);
  run.seed = m_cfg.system.seed;
  run.frames_written = m_trajectory.framesWritten();
  m_engine.saveCheckpoint(m_folder, run);
  m_last_step = m_engine.step();
  m_last_time = Clock::now();
  m_trajectory.checkpointWritten(m_engine.checkpointPath(m_folder), m_last_step);
}

// ---- profile.csv -------------------------------------------------------------------------------

void writeProfile(const RunEngine& engine, const fs::path& path, const std::string& command_line,
                  std::int64_t steps, double loop_seconds, std::int64_t neighbor_builds,
                  std::int64_t slow_evaluations) {
  std::vector<std::string> columns = {"steps", "N", "loop_s"};
  std::vector<double> row = {static_cast<double>(steps), static_cast<double>(engine.size()),
                             loop_seconds};
  double sum = 0.0;
  for (const auto& [name, s] : engine.phaseSeconds()) {
    std::string col;  // "PPPM k-space" -> "pppm_k_space"
    for (char c : name)
      col += std::isalnum(static_cast<unsigned char>(c)) ? static_cast<char>(std::tolower(c)) : '_';
    while (col.find("__") != std::string::npos) col.erase(col.find("__"), 1);
    if (!col.empty() && col.back() == '_') col.pop_back();
    columns.push_back(col + "_s");
    row.push_back(s);
    sum += s;
  }
  columns.push_back("other_s");
  row.push_back(loop_seconds - sum);
  columns.push_back("neighbor_builds");
  row.push_back(static_cast<double>(neighbor_builds));
  columns.push_back("slow_evaluations");
  row.push_back(static_cast<double>(slow_evaluations));
  common::Provenance prov(command_line);
  prov.add("version", common::versionString());
  prov.add("backend", engine.description());
  // the set-up the timings belong to, for scripts (the log lines are for people)
  prov.add("box_L", engine.box());
  prov.add("dt", engine.dt());
  prov.add("t_end", engine.time());
  if (const CoulombSetup* cs = engine.coulombSetup()) {
    prov.add("coulomb_method", cs->method);
    prov.add("coulomb_alpha", cs->alpha);
    prov.add("coulomb_r_cut", cs->r_cut);
    if (cs->method == "pppm") {
      prov.add("coulomb_mesh", cs->mesh);
      prov.add("coulomb_order", cs->order);
    } else {
      prov.add("coulomb_k_max", cs->k_max);
    }
    prov.add("coulomb_estimated_error", cs->estimated_error);
    prov.add("coulomb_r_fast", cs->r_fast);
    prov.add("coulomb_every", cs->every);
    prov.add("coulomb_every_max", cs->every_max);
  }
  common::CsvWriter w(path.string(), prov, columns, /*overwrite=*/true);
  w.row(row);
  w.close();
}

}  // namespace granagg::md
