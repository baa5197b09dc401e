#pragma once
// peelcd: image-space collision detection between triangle meshes through surface peeling.
// The umbrella header: the core API (meshes, options, the detector, the collision API, the CPU
// image stage), mesh and scene files, and the GL stage with the contexts this installation has.
// Finer-grained headers live beside it (peelcd/core/..., peelcd/gl/..., peelcd/io/...).
#include "peelcd/version.h"

#include "peelcd/core/frame.h"
#include "peelcd/core/mesh.h"
#include "peelcd/core/options.h"
#include "peelcd/core/pairs.h"
#include "peelcd/core/primitives.h"
#include "peelcd/core/exact/bvh.h"
#include "peelcd/core/exact/depth.h"
#include "peelcd/core/exact/narrow_phase.h"
#include "peelcd/core/exact/proximity.h"
#include "peelcd/core/exact/reference.h"
#include "peelcd/core/exact/relation.h"
#include "peelcd/core/exact/self.h"
#include "peelcd/core/image/cpu_stage.h"
#include "peelcd/core/image/detector.h"
#include "peelcd/core/image/id_map.h"
#include "peelcd/core/image/image_stage.h"
#include "peelcd/core/image/planner.h"
#include "peelcd/core/image/view.h"
#include "peelcd/core/world/collision.h"
#include "peelcd/core/world/world.h"
#if __has_include("peelcd/io/mesh_io.h")
#include "peelcd/io/mesh_io.h"
#include "peelcd/io/scene.h"
#endif
#if __has_include("peelcd/gl/gl_stage.h")
#include "peelcd/gl/context.h"
#include "peelcd/gl/gl_stage.h"
#include "peelcd/gl/pipeline.h"
#endif
#if __has_include("peelcd/gl_egl/egl_context.h")
#include "peelcd/gl_egl/egl_context.h"
#endif
#if __has_include("peelcd/gl_osmesa/osmesa_context.h") && PEELCD_HAVE_OSMESA
#include "peelcd/gl_osmesa/osmesa_context.h"
#endif
// The image stage by backend name (make_image_stage("osmesa" | "egl" | "cpu")): "cpu" with
// peelcd::core alone, "egl" and "osmesa" where the program links their components.
#include "peelcd/backends.h"
