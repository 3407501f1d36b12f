// The last step of every output file's write: its finished temporary takes the file's name.
#pragma once

#include <string>

namespace ls {

// Renames `temp` to `path`; either way the interrupt handler no longer has a temporary to remove
// (set_partial_file).  Where the rename fails (`path` is a directory, say) the temporary is removed
// and an InputError says which file could not be written and why, in one line.
void replace_file(const std::string& temp, const std::string& path);

}  // namespace ls
