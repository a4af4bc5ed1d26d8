# Sources of core/scene (one .h/.cpp pair per concept). glTF files are read with
# tinygltf (Debian's shared libtinygltf), which only gltf_loader, gltf_accessor
# and gltf_materials include.
target_link_libraries(modestack_core PRIVATE TinyGLTF::TinyGLTF)
target_sources(modestack_core PRIVATE
  ${CMAKE_CURRENT_LIST_DIR}/scene.cpp
  ${CMAKE_CURRENT_LIST_DIR}/builtin_scenes.cpp
  ${CMAKE_CURRENT_LIST_DIR}/gltf_notices.cpp
  ${CMAKE_CURRENT_LIST_DIR}/gltf_keyframes.cpp
  ${CMAKE_CURRENT_LIST_DIR}/gltf_animation.cpp
  ${CMAKE_CURRENT_LIST_DIR}/gltf_accessor.cpp
  ${CMAKE_CURRENT_LIST_DIR}/gltf_materials.cpp
  ${CMAKE_CURRENT_LIST_DIR}/gltf_lights.cpp
  ${CMAKE_CURRENT_LIST_DIR}/gltf_scene.cpp
  ${CMAKE_CURRENT_LIST_DIR}/gltf_loader.cpp)
