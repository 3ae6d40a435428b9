# The GLSL of the GL renderer, embedded at build time (included by renderer/CMakeLists.txt).
#
# Each file under renderer/gl/shaders/ is one piece of a stage, exactly as the C++ passes it to
# OpenGL: .vert and .frag files are whole stages (#version first); a .glsl file is a piece that
# the C++ joins to others after #version, #define and constant lines it writes (sky_shaders.cpp,
# ellipsoid_shaders.cpp, automaton_renderer.cpp, shadow_map.cpp, target_renderer.cpp). Vertex
# pieces end in _vertex.glsl; the other .glsl pieces are fragment code.
#
# nephele_embed_glsl writes one header per C++ file into the build tree,
# renderer/gl/shaders/<header> under ${NEPHELE_GLSL_INCLUDE_DIR}, that holds its pieces as
# `inline constexpr char kName[]` in namespace nephele::glsl::<group>, and writes it again when
# a piece changes. Nothing is read at run time: the binary carries the text.

set(NEPHELE_GLSL_DIR ${CMAKE_CURRENT_LIST_DIR})
set(NEPHELE_GLSL_INCLUDE_DIR ${PROJECT_BINARY_DIR}/generated)

# nephele_embed_glsl(TARGET HEADER GROUP NAME FILE [NAME FILE ...]): the header HEADER, holding
# each FILE (relative to renderer/gl/shaders, or an absolute path) as constant NAME in
# nephele::glsl::GROUP, compiled into TARGET.
function(nephele_embed_glsl target header group)
  set(output ${NEPHELE_GLSL_INCLUDE_DIR}/renderer/gl/shaders/${header})
  set(pieces "")
  set(files "")
  set(rest ${ARGN})
  while(rest)
    list(POP_FRONT rest name file)
    if(NOT file)
      message(FATAL_ERROR "nephele_embed_glsl(${header}): ${name} has no file")
    endif()
    if(IS_ABSOLUTE ${file})
      set(path ${file})
    else()
      set(path ${NEPHELE_GLSL_DIR}/${file})
    endif()
    if(NOT EXISTS ${path})
      message(FATAL_ERROR "nephele_embed_glsl(${header}): ${path} does not exist")
    endif()
    list(APPEND pieces "${name}=${path}")
    list(APPEND files ${path})
  endwhile()
  string(REPLACE ";" "|" pieces "${pieces}")
  add_custom_command(OUTPUT ${output}
    COMMAND ${CMAKE_COMMAND} -DOUTPUT=${output} -DNAMESPACE=nephele::glsl::${group}
            -DPIECES=${pieces} -P ${NEPHELE_GLSL_DIR}/embed_glsl.cmake
    DEPENDS ${NEPHELE_GLSL_DIR}/embed_glsl.cmake ${files}
    COMMENT "Embedding GLSL into ${header}"
    VERBATIM)
  target_sources(${target} PRIVATE ${output})
  target_include_directories(${target} PRIVATE ${NEPHELE_GLSL_INCLUDE_DIR})
endfunction()

# The formulas the GL renderer shares with the CPU reference, written once in the common ground
# of C++ and GLSL (world/formulas/prelude.h): the prelude first, then each family. sky_shaders.cpp
# (formulaSource) pastes them ahead of sky/common.glsl, so every stage that holds the view chunk
# holds them, and ahead of the shadow map's fragment stage.
set(NEPHELE_FORMULA_DIR ${PROJECT_SOURCE_DIR}/world/formulas)
nephele_embed_glsl(nephele_renderer formulas_glsl.h formulas
  kPrelude ${NEPHELE_FORMULA_DIR}/prelude.h  # real, FORMULA
  kTable ${NEPHELE_FORMULA_DIR}/table.h      # a table's cell
  kAir ${NEPHELE_FORMULA_DIR}/air.h          # slabs, haze, shafts
  kShading ${NEPHELE_FORMULA_DIR}/shading.h  # Gardner eq. 8, 9, 11, far heaps' diffuse
  kSea ${NEPHELE_FORMULA_DIR}/sea.h          # Fresnel, foam, glint
  kEllipsoid ${NEPHELE_FORMULA_DIR}/ellipsoid.h  # ray hit, limb function
  kHeap ${NEPHELE_FORMULA_DIR}/heap.h            # heap light, two-stream transmittance
  kFarDeck ${NEPHELE_FORMULA_DIR}/far_deck.h     # a far deck's apparent cover
  kRegion ${NEPHELE_FORMULA_DIR}/region.h        # a region's bands and threshold
  kTexture ${NEPHELE_FORMULA_DIR}/texture.h      # the terms a footprint resolves, T from sums
  kShadow ${NEPHELE_FORMULA_DIR}/shadow.h        # a lobe's shadow, ground and target light
  kVolume ${NEPHELE_FORMULA_DIR}/volume.h)       # phase functions, scattering
nephele_embed_glsl(nephele_renderer sky_glsl.h sky
  kCommon sky/common.glsl             # the view, output, air, background and targets
  kLayers sky/layers.glsl             # textured cloud layers
  kClipmapBake sky/clipmap_bake.glsl  # main() of the clipmap ring's bake pass
  kPolygonVertex polygon.vert)        # a convex screen polygon, for every screen-space pass
nephele_embed_glsl(nephele_renderer ellipsoid_glsl.h ellipsoid
  kRecords ellipsoid/records.glsl     # the per-ellipsoid record (both stages)
  kCloud ellipsoid/cloud.glsl         # ray-quadric hit, solid texture, limb, shading
  kFusedCentre ellipsoid/fused_centre.glsl
  kFusedPerPixel ellipsoid/fused_per_pixel.glsl
  kFusedBlend ellipsoid/fused_blend.glsl
  kFusedResolve ellipsoid/fused_resolve.glsl
  kTile ellipsoid/tile.glsl
  kComposite ellipsoid/composite.glsl
  kImpostor ellipsoid/impostor.glsl
  kVeil ellipsoid/veil.glsl
  kFusedCentreVertex ellipsoid/fused_centre_vertex.glsl
  kTileVertex ellipsoid/tile_vertex.glsl
  kRectsVertex ellipsoid/rects_vertex.glsl
  kImpostorVertex ellipsoid/impostor_vertex.glsl)
nephele_embed_glsl(nephele_renderer automaton_glsl.h automaton
  kVolumePass automaton/volume_pass.glsl)
nephele_embed_glsl(nephele_renderer floor_glsl.h floor_pass
  kFloorFragment floor.frag)
nephele_embed_glsl(nephele_renderer shadow_map_glsl.h shadow_map
  kVertex shadow_map/footprint_vertex.glsl
  kFragment shadow_map/sunlight.glsl)
nephele_embed_glsl(nephele_renderer target_glsl.h target
  kVertex target/mesh.vert
  kFragment target/shading.glsl)
