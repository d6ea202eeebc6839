// lanemap-channels: prints the channel registry (name, type, rate, publisher) as a table or TSV.
#include "processes/framework/channels.h"

#include <CLI/CLI.hpp>

#include <cstdio>

int main(int argc, char** argv) {
  CLI::App app("lanemap-channels: every LCM channel of lanemap with its type and nominal rate");
  bool tsv = false;
  app.add_flag("--tsv", tsv, "tab-separated, no header (for scripts)");
  CLI11_PARSE(app, argc, argv);
  if (!tsv) std::printf("%-22s %-26s %8s  %-20s %s\n", "CHANNEL", "TYPE", "RATE_HZ", "PUBLISHER", "WHAT");
  for (const auto& c : lanemap::channels::kRegistry) {
    if (tsv) {
      std::printf("%s\t%s\t%g\t%s\n", c.name, c.type, c.rate_hz, c.publisher);
    } else {
      std::printf("%-22s %-26s %8g  %-20s %s\n", c.name, c.type, c.rate_hz, c.publisher, c.summary);
    }
  }
  return 0;
}
