// The driver that runs one meshing job on several processes (`mpirun -np P polysquare mesh ...`). It owns every
// MPI call of polysquare; the stages see the processes only as a WorkSharing (core/work_sharing.h).
//
// Started without mpirun (or in a build without MPI) it is one process and changes nothing.
#pragma once

#include <memory>

#include "polysquare/core/work_sharing.h"

namespace polysquare {

class MpiDriver {
 public:
  /// Starts MPI when this process was launched by an MPI launcher (Open MPI's or a PMIx one); else nothing.
  MpiDriver(int& argc, char**& argv);
  ~MpiDriver();  ///< finalizes MPI when it was started here
  MpiDriver(const MpiDriver&) = delete;
  MpiDriver& operator=(const MpiDriver&) = delete;

  bool active() const { return processes_ > 1; }
  int rank() const { return rank_; }
  int processes() const { return processes_; }
  /// Processes of this job on this machine: the CLI divides the cores among them.
  int local_processes() const { return local_processes_; }
  /// The processes as the stages see them (one process: nullptr).
  std::shared_ptr<const WorkSharing> sharing() const { return sharing_; }
  /// The cores of this machine divided among this job's processes on it (at least 1).
  int threads_per_process() const;
  /// Ends every process of the job with `code` (an error that only this process met, which the others may be
  /// waiting on); returns only when MPI is not running.
  void abort(int code) const;
  /// Whether this build can run on several processes.
  static bool built_with_mpi();

 private:
  bool started_ = false;
  int rank_ = 0, processes_ = 1, local_processes_ = 1;
  std::shared_ptr<const WorkSharing> sharing_;
};

}  // namespace polysquare
