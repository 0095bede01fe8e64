// Base64 (RFC 4648, standard alphabet, '=' padding) for the HTML report: binary replay data
// and meshes travel inside small .js files, so the page opens from disk (file:// forbids
// fetch) and the browser decodes them with atob().
#pragma once

#include <cstddef>
#include <string>
#include <string_view>
#include <vector>

namespace kuavo::report {

std::string base64_encode(const void* data, std::size_t size);
inline std::string base64_encode(std::string_view bytes) { return base64_encode(bytes.data(), bytes.size()); }

// false on a character outside the alphabet or a length that is not a multiple of 4.
bool base64_decode(std::string_view text, std::vector<unsigned char>& out);

}  // namespace kuavo::report
