# Tests that take more than about 8 s on one core (ctest -L slow selects them, -LE slow skips
# them). Read by ctest after the discovered GoogleTest lists (tests/CMakeLists.txt), so each entry
# names a discovered test and gives its full label list.
set_tests_properties(
  Remesh.WholeRetessellationKeepsTheSurfacesWithinTolerance
  RobotsCableFinger.ConvergesOverItsRangeAndCurlsUpInPlane
  RobotGrid.MultiSegmentGripperCurlsInPlane
  RobotGrid.FingerManipulatorIsPlanarAndMirrorSymmetric
  NlpSolvers.SamePositionsAsLocalGlobalOnATetBar
  NlpSolvers.IpoptMinimisesBlendedBodiesCeresRejectsThem
  PROPERTIES LABELS "solver;slow")
