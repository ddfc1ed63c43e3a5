#pragma once
/// \file dataset_mpi.hpp
/// `mpirun -n N softkin dataset ...` (docs/cluster.md): the samples go out in units of one
/// warm-start block (--block), handed out by rank 0 as ranks ask for work, so that slow regions of
/// the workspace do not leave ranks idle. Rank 0 computes units too and answers the others between
/// its own samples. Each unit is a shard file of the dataset (learn/dataset.hpp), written as it
/// goes in OUT.parts/; a killed job rerun with the same command resumes each unit where it
/// stopped. When every unit is complete, rank 0 merges them into OUT (equal to a one-process run,
/// bit for bit, as --shard and --merge are) and removes OUT.parts/.
#include "softkin/ik/kinematics.hpp"
#include "softkin/learn/dataset.hpp"

namespace softkin {

/// Generates the dataset of `run` (its shard fields are ignored) across the ranks of the job, as
/// the file comment says, and returns the job's totals on every rank (count and first: the whole
/// dataset). If run.out exists already (a finished job, or a one-process file), rank 0 resumes or
/// checks it alone, as `softkin dataset` does. Outside an MPI job (MpiJob(), mpi_job.hpp) it is
/// GenerateDataset of the whole. A rank that fails prints its error and aborts the job
/// (MpiAbortJob); the completed units stay for the rerun.
DatasetRunSummary GenerateDatasetMpi(Kinematics& kin, const DatasetSampling& sampling,
                                     const DatasetRunOptions& run);

}  // namespace softkin
