# Writes a C++ source holding drivers/view/view_page.html as a string, so the binary serves the page
# without knowing where the repository is. Called at build time with PAGE and OUTPUT set.
file(READ ${PAGE} text)
string(FIND "${text}" ")voca_page\"" clash)
if(NOT clash EQUAL -1)
  message(FATAL_ERROR "${PAGE} contains the raw string's end marker )voca_page\"")
endif()
file(WRITE ${OUTPUT}.tmp
  "// Generated from drivers/view/view_page.html by drivers/view/embed_page.cmake; do not edit.\n"
  "#include \"drivers/view/view_page.h\"\n\n"
  "namespace voca::view {\n\n"
  "std::string_view viewPageHtml() {\n"
  "  static constexpr std::string_view kPage = R\"voca_page(${text})voca_page\";\n"
  "  return kPage;\n"
  "}\n\n"
  "}  // namespace voca::view\n")
file(COPY_FILE ${OUTPUT}.tmp ${OUTPUT} ONLY_IF_DIFFERENT)
