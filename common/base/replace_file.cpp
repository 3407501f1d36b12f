#include "common/base/replace_file.h"

#include "common/base/interrupt.h"
#include "common/model/scene.h"  // InputError

#include <filesystem>
#include <system_error>

namespace ls {

void replace_file(const std::string& temp, const std::string& path) {
  std::error_code ec;
  std::filesystem::rename(temp, path, ec);
  set_partial_file(nullptr);
  if (!ec) return;
  std::error_code ignored;
  std::filesystem::remove(temp, ignored);
  const std::string why = std::filesystem::is_directory(path, ignored) ? "it is a directory" : ec.message();
  throw InputError("cannot write '" + path + "': " + why);
}

}  // namespace ls
