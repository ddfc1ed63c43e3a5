// experiments/mpi_job.cpp compiled without MPI (as in a build where CMake finds none): the job is
// one process, and a launcher that starts several processes is refused with a message that says
// MPI is unavailable and what to install.
#include "softkin/experiments/mpi_job.hpp"

#include <gtest/gtest.h>

#include <cstdlib>
#include <stdexcept>
#include <string>

namespace softkin {
namespace {

/// Sets an environment variable for the length of a test.
class ScopedEnv {
 public:
  ScopedEnv(const char* name, const char* value) : name_(name) { setenv(name, value, 1); }
  ~ScopedEnv() { unsetenv(name_); }

 private:
  const char* name_;
};

TEST(NoMpi, TheBuildSaysMpiIsUnavailable) {
  EXPECT_FALSE(HaveMpi());
  EXPECT_NE(MpiSupportNote().find("MPI: unavailable"), std::string::npos) << MpiSupportNote();
  EXPECT_NE(MpiSupportNote().find("libopenmpi-dev"), std::string::npos);
}

TEST(NoMpi, OneProcessRunsAsAJobOfOne) {
  EXPECT_NO_THROW(RequireMpiIfLaunched("dataset --out d.csv"));
  EXPECT_EQ(MpiJob().size, 1);
  EXPECT_TRUE(MpiJob().root());
  EXPECT_FALSE(MpiStarted());
  MpiSharedCounter counter;
  EXPECT_EQ(counter.Next(), 0);
  EXPECT_EQ(counter.Next(), 1);
  EXPECT_EQ(counter.Next(), 2);
  const long long in[2] = {3, 4};
  long long out[2] = {0, 0};
  MpiSumOverRanks(in, out, 2);
  EXPECT_EQ(out[0], 3);
  EXPECT_EQ(out[1], 4);
  EXPECT_EQ(MpiMaxOverRanks(2.5), 2.5);
}

TEST(NoMpi, SeveralLaunchedProcessesAreRefusedWithTheReason) {
  for (const char* var : {"OMPI_COMM_WORLD_SIZE", "PMI_SIZE"}) {
    ScopedEnv size(var, "4");
    EXPECT_EQ(LaunchedMpiSize(), 4);
    try {
      RequireMpiIfLaunched("run fig5_5_architecture");
      ADD_FAILURE() << var << "=4 was accepted";
    } catch (const std::invalid_argument& e) {
      const std::string m = e.what();
      EXPECT_NE(m.find("run fig5_5_architecture: started by an MPI launcher with 4 processes"),
                std::string::npos)
          << m;
      EXPECT_NE(m.find("MPI is unavailable"), std::string::npos) << m;
      EXPECT_NE(m.find("install libopenmpi-dev"), std::string::npos) << m;
    }
  }
  // Slurm's srun with PMIx: the size is SLURM_NTASKS.
  ScopedEnv rank("PMIX_RANK", "1"), tasks("SLURM_NTASKS", "3");
  EXPECT_EQ(LaunchedMpiRank(), 1);
  EXPECT_EQ(LaunchedMpiSize(), 3);
  EXPECT_THROW(RequireMpiIfLaunched("dataset --out d.csv"), std::invalid_argument);
}

}  // namespace
}  // namespace softkin
