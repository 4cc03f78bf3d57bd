# Writes a C++ source holding every configs/*.json as a string, so the shipped configurations can
# be named on the command line (--config kitti) without knowing where the repository is.
# Called at build time with CONFIG_DIR and OUTPUT set.
file(GLOB config_files "${CONFIG_DIR}/*_vo.json")
list(SORT config_files)
set(entries "")
foreach(file ${config_files})
  get_filename_component(stem ${file} NAME_WE)
  string(REGEX REPLACE "_vo$" "" name ${stem})
  file(READ ${file} text)
  string(APPEND entries "    {\"${name}\", R\"voca_json(${text})voca_json\"},\n")
endforeach()
file(WRITE ${OUTPUT}.tmp
  "// Generated from configs/*_vo.json by formats/config/embed_configs.cmake; do not edit.\n"
  "#include \"formats/config/builtin_configs.h\"\n\n"
  "namespace voca {\n\n"
  "std::span<const BuiltinConfig> builtinConfigs() {\n"
  "  static constexpr BuiltinConfig kConfigs[] = {\n${entries}  };\n"
  "  return kConfigs;\n"
  "}\n\n"
  "}  // namespace voca\n")
file(COPY_FILE ${OUTPUT}.tmp ${OUTPUT} ONLY_IF_DIFFERENT)
