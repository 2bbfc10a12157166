// Invariant checks that stay on in release builds: a broken invariant is a
// bug in this program, so it aborts loudly instead of writing wrong numbers.
#ifndef RADIOSITY_CHECK_H
#define RADIOSITY_CHECK_H

#include <cstdio>
#include <cstdlib>

#define CHECK(cond)                                                        \
  do {                                                                     \
    if (!(cond)) {                                                         \
      std::fprintf(stderr, "radiosity: internal error: %s:%d: CHECK(%s)\n", \
                   __FILE__, __LINE__, #cond);                             \
      std::abort();                                                        \
    }                                                                      \
  } while (0)

#endif
