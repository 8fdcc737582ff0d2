// rosconsole (log4cxx) converts every line through the C library's character set, which stays
// ASCII until the program sets its locale: "Poincaré" came out as "Poincar??". Nodes call this
// before their first log line. LC_CTYPE only: number formatting (LC_NUMERIC) stays "C".
#pragma once

#include <langinfo.h>

#include <clocale>
#include <cstring>

namespace gear_dynamics {

inline void use_utf8_console() {
  std::setlocale(LC_CTYPE, "");  // the user's, e.g. C.UTF-8 or en_US.UTF-8
  if (std::strcmp(nl_langinfo(CODESET), "UTF-8") != 0) std::setlocale(LC_CTYPE, "C.UTF-8");
}

}  // namespace gear_dynamics
