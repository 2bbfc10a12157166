// Numbers as text in the outputs (result.csv, result.ply): the same
// characters printf's %.9g and %d give, by std::to_chars, which does not
// parse a format or consult the locale. At 10^6 vertices snprintf made
// result.ply in 0.57 s, most of the end of a run.
#ifndef RADIOSITY_TEXTNUM_H
#define RADIOSITY_TEXTNUM_H

#include <charconv>
#include <string>

// Appends v as %.9g prints it (9 significant digits: a float survives the
// round trip, a double is near enough for results).
inline void AppendG9(std::string* s, double v) {
  char buf[32];
  const auto r = std::to_chars(buf, buf + sizeof buf, v, std::chars_format::general, 9);
  s->append(buf, r.ptr);
}

inline void AppendInt(std::string* s, long v) {
  char buf[24];
  const auto r = std::to_chars(buf, buf + sizeof buf, v);
  s->append(buf, r.ptr);
}

#endif
