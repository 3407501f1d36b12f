// A table of text cells printed as Markdown (for people and the README) and as CSV (for scripts).
#pragma once

#include <string>
#include <vector>

namespace ls {

struct Table {
  std::vector<std::string> header;
  std::vector<std::vector<std::string>> rows;

  std::string markdown() const;
  std::string csv() const;
};

std::string fixed(double value, int decimals);  // "%.*f"; "-" for NaN
std::string rmse_text(double value);            // ".0123", as the paper prints RMSE
void write_text_file(const std::string& path, const std::string& text);  // throws on failure

}  // namespace ls
