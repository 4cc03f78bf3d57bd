#pragma once
// The live view's web page (drivers/view/view_page.html: one self-contained file, its script and style
// inline, nothing fetched from the network), compiled into the binary at build time.

#include <string_view>

namespace voca::view {

std::string_view viewPageHtml();

}  // namespace voca::view
