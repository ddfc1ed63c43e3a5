#pragma once
/// \file ccx_run.hpp
/// Running the CalculiX solver `ccx` (Debian package calculix-ccx) as a child process, shared by
/// the eigenstrain baseline (calculix.hpp) and the pressure-loaded FEM (calculix_pressure.hpp):
/// finding the executable, a temporary work folder, the run itself (no shell, a wall-clock limit,
/// each converged increment time-stamped from the job's status file) and the reason it stopped.
#include <chrono>
#include <filesystem>
#include <string>
#include <vector>

namespace softkin {

/// Path of the ccx executable found on PATH, or "" if there is none.
std::string FindCcx();

/// The message given when ccx is missing.
std::string CcxMissingMessage();

/// Number of converged increments listed so far in a ccx .sta file (its lines "STEP INC ATT ITRS
/// ..." whose attempt column has no 'U', the mark of an attempt that was cut back). 0 if the file
/// does not exist yet. Used to time-stamp increments while ccx runs.
int CountConvergedIncrements(const std::string& sta_path);

/// A fresh temporary folder (softkin_ccx_XXXXXX), removed with its content on destruction unless
/// `keep`. path() is empty if it could not be created.
class CcxWorkFolder {
 public:
  explicit CcxWorkFolder(bool keep);
  ~CcxWorkFolder();
  CcxWorkFolder(const CcxWorkFolder&) = delete;
  CcxWorkFolder& operator=(const CcxWorkFolder&) = delete;
  const std::filesystem::path& path() const { return path_; }

 private:
  std::filesystem::path path_;
  bool keep_;
};

/// How a ccx run ended.
struct CcxRun {
  bool started = false;    ///< the process was created
  bool timed_out = false;  ///< killed at the wall-clock limit
  /// Seconds since `t0` at which each converged increment appeared in job.sta, in order.
  std::vector<double> increment_wall_s;
  std::string last_error;  ///< the last line of ccx's output that mentions an error ("" if none)
};

/// Runs `ccx -i job` in `work` (which holds job.inp), its output going to work/ccx.log, with at
/// most 2 OpenMP threads unless OMP_NUM_THREADS says otherwise. Kills it after `time_limit_s`
/// seconds since `t0` (0: no limit).
CcxRun RunCcxJob(const std::string& ccx, const std::filesystem::path& work, double time_limit_s,
                 std::chrono::steady_clock::time_point t0);

}  // namespace softkin
