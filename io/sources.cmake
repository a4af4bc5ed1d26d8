target_sources(modestack_io PRIVATE
  ${CMAKE_CURRENT_LIST_DIR}/sequence.cpp
  ${CMAKE_CURRENT_LIST_DIR}/layers.cpp
  ${CMAKE_CURRENT_LIST_DIR}/frame_header.cpp
  ${CMAKE_CURRENT_LIST_DIR}/detail/open_image.cpp
  ${CMAKE_CURRENT_LIST_DIR}/sequence_reader.cpp
  ${CMAKE_CURRENT_LIST_DIR}/detail/zip_scanline_reader.cpp
  ${CMAKE_CURRENT_LIST_DIR}/detail/exr_core.cpp
  ${CMAKE_CURRENT_LIST_DIR}/frame_output.cpp
  ${CMAKE_CURRENT_LIST_DIR}/detail/zip_scanline_writer.cpp
  ${CMAKE_CURRENT_LIST_DIR}/half_conversion.cpp
  ${CMAKE_CURRENT_LIST_DIR}/text_output.cpp
  ${CMAKE_CURRENT_LIST_DIR}/temporary_file.cpp
  ${CMAKE_CURRENT_LIST_DIR}/color_management.cpp
  ${CMAKE_CURRENT_LIST_DIR}/contact_sheet.cpp
  ${CMAKE_CURRENT_LIST_DIR}/mask_image.cpp
  ${CMAKE_CURRENT_LIST_DIR}/png_encoding.cpp
  ${CMAKE_CURRENT_LIST_DIR}/stage_files.cpp)
