// Scenes: simulate only the effects a scene calls for (docs/design.md, "Scenes", docs/scenes.md).
//
// A scene names the active effects, the operating point, the analyses and the inputs and outputs
// of interest (model.hpp: Scene). apply_scene() turns a model and one of its scenes into a pruned
// model, before anything is derived: inactive force elements are removed (a bushing can lose its
// stiffness or its damping part), inputs not of interest are set to zero and dropped, outputs not
// of interest are dropped, the operating point is overridden, and the velocity-quadratic inertia
// terms are dropped where they cannot contribute (linearization about rest). The selection it
// (Model::selection()) says which kernels the scene's analyses need and what became of each
// effect, for the emitter's header and manifest.
#pragma once

#include "mbsgen/generator/model/model.hpp"

#include <string>
#include <vector>

namespace mbsgen {

/// Prunes `model` for the scene `scene` ("full" for the whole model: a copy, every kernel). The
/// result keeps every parameter (the kernels' parameter vector is the same for all scenes of a
/// model), has no scenes itself, and says in selection() what the scene kept. Throws
/// std::invalid_argument naming the known scenes when there is no such scene.
Model apply_scene(const Model& model, const std::string& scene);

/// Every effect of a model, all active (the effects of the full scene).
std::vector<EffectState> effects_of(const Model& model);

/// Checks a scene against its model: every effect, input and output it names exists (with a
/// "did you mean" suggestion), nothing is listed twice, the operating-point override names
/// coordinates and depends on parameters only, and the frequency range is sensible. Throws
/// ModelError at the offending name.
void check_scene(const Model& model, const Scene& scene);

/// The kernels an analysis uses (operating_point is always emitted besides).
std::vector<std::string> kernels_of(Analysis analysis);

}  // namespace mbsgen
