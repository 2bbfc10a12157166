// The master's run as main takes it (app.h): here the writers that write
// pictures while the run goes on.
#include <chrono>
#include <future>
#include <string>

#include <gtest/gtest.h>

#include "app.h"

namespace {

// The writes run beside one another (and beside the caller): the first
// waits for the second, which starts only after it.
TEST(Writers, WritesRunAtOnce) {
  Writers w;
  std::promise<void> second_ran;
  std::shared_future<void> ran = second_ran.get_future().share();
  w.Start([ran](std::string* err) {
    if (ran.wait_for(std::chrono::seconds(10)) == std::future_status::ready) return true;
    *err = "the second write did not run while the first waited";
    return false;
  });
  w.Start([&second_ran](std::string*) {
    second_ran.set_value();
    return true;
  });
  EXPECT_EQ(w.Wait(), "");
}

// Wait() gives the first failed write's error in the order they were
// started, one without a message a message of its own, and "" once all
// are done.
TEST(Writers, WaitGivesTheFirstError) {
  Writers w;
  w.Start([](std::string*) { return true; });
  w.Start([](std::string* err) {
    *err = "b: disk full";
    return false;
  });
  w.Start([](std::string* err) {
    *err = "c: disk full";
    return false;
  });
  EXPECT_EQ(w.Wait(), "b: disk full");
  EXPECT_EQ(w.Wait(), "");
  w.Start([](std::string*) { return false; });
  EXPECT_FALSE(w.Wait().empty());
}

}  // namespace
