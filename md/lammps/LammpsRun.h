#pragma once
/// \file LammpsRun.h
/// A run of granagg's model on LAMMPS across MPI ranks (the driver behind granagg-lammps): owns
/// the LAMMPS instance, registers fix granagg/charging, feeds it the translated input
/// (LammpsInput.h) and runs to run.t_end in chunks of output.observable_interval steps
/// (`run N pre no post no`: no setup between chunks, the same trajectory as one `run`),
/// sampling granagg's observables after each chunk.
///
/// Output folder (rank 0 writes; gathering to rank 0 holds everything of a frame in one rank's
/// memory, fine up to ~1e7 particles):
///   config.toml        the resolved configuration (md::toToml)
///   initial.data       the initial state as a LAMMPS data file
///   lammps.in          the generated LAMMPS input (also on the log)
///   log.lammps         LAMMPS's own log
///   observables.csv    step, time and the observables of granagg md (md::Observables), per
///                      sample; the Coulomb energy is LAMMPS's (pair coul/long + kspace)
///   final_state.csv    x,y,z,vx,vy,vz,q per particle in id order (a CSV initial state)
///   collisions.csv     with record_collisions: step,id_lo,id_hi,xi_dot,dq_lo per collision
#include <mpi.h>

#include <string>

#include "md/config/MdConfig.h"

namespace granagg::md::lammps {

struct LammpsRunOptions {
  std::string out;                 ///< output folder: must not exist or be empty unless overwrite
  bool overwrite = false;          ///< --force
  bool record_collisions = false;  ///< write collisions.csv
  bool quiet = false;              ///< no log lines
  std::string command_line;        ///< for provenance
};

/// Runs `config` on LAMMPS over `comm` (collective: every rank calls it with the same
/// arguments). Bad input (a key LAMMPS cannot honour, an unusable initial state, an output folder
/// in the way) throws std::invalid_argument on every rank, before anything is written; other
/// failures std::runtime_error. LAMMPS's own errors end the process (LAMMPS is built without
/// exceptions), after rank 0 has printed LAMMPS's error line on stderr.
void runOnLammps(const MdConfig& config, const LammpsRunOptions& options, MPI_Comm comm);

}  // namespace granagg::md::lammps
