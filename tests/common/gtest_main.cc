// main() of every test binary: gtest's, plus one listener. When a suite's SetUpTestSuite fails
// (an exception, a fatal assertion), gtest marks each of its tests "[  SKIPPED ]"; ctest, whose
// gtest_discover_tests treats that text as a skip whatever the exit status, would then count a
// broken suite as skipped and the run as passed. The listener ends the process with status 1
// before gtest prints that line, so ctest sees a failure.
#include <gtest/gtest.h>

#include <cstdio>
#include <cstdlib>

namespace {

class FailBrokenSuites : public ::testing::EmptyTestEventListener {
  void OnTestStart(const ::testing::TestInfo& info) override {
    const ::testing::TestSuite* suite = ::testing::UnitTest::GetInstance()->current_test_suite();
    if (suite && suite->ad_hoc_test_result().Failed()) {
      std::fprintf(stderr, "%s.%s: its suite's SetUpTestSuite failed (above): failing, not skipping\n",
                   info.test_suite_name(), info.name());
      std::fflush(stdout);
      std::_Exit(1);
    }
  }
};

}  // namespace

int main(int argc, char** argv) {
  ::testing::InitGoogleTest(&argc, argv);
  ::testing::UnitTest::GetInstance()->listeners().Append(new FailBrokenSuites);
  return RUN_ALL_TESTS();
}
