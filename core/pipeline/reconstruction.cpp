#include "pipeline/reconstruction.h"

#include "pipeline/alpha_stage.h"
#include "pipeline/auto_filter.h"
#include "pipeline/filter_catalog.h"
#include "util/error.h"

namespace mcr {

std::unique_ptr<Filter> make_committed_filter(const std::string& filter,
                                              const std::vector<std::pair<std::string, std::string>>& params) {
  std::unique_ptr<Filter> f = make_catalog_filter(filter);
  for (const auto& kv : params) f->set_text(kv.first, kv.second);
  f->commit();
  return f;
}

std::string parameters_text(const Filter& filter) {
  std::string params;
  for (const auto& kv : filter.params().values())
    params += (params.empty() ? "" : " ") + kv.first + "=" + param_value_text(kv.second);
  return params;
}

namespace {

// A filter like `f`: the same kind, every setting given to f given to it, committed.
std::unique_ptr<Filter> same_filter(const Filter& f) {
  std::unique_ptr<Filter> g = make_catalog_filter(f.info().name);
  for (const auto& kv : f.params().values())
    if (f.params().was_set(kv.first)) g->set(kv.first, kv.second);
  return g;
}

}  // namespace

Filter* Reconstruction::alpha_filter() {
  if (!alpha_) return nullptr;
  if (!alpha_->filter) alpha_->filter = make_alpha_filter(filter());
  return alpha_->filter.get();
}

Reconstruction::Reconstruction(std::unique_ptr<Filter> filter, bool accumulate) : accumulate_(accumulate) {
  if (!filter) throw Error(Errc::Internal, "Reconstruction without a filter");
  const bool split = uses_light_passes(filter->params());
  if (split) {
    // The light passes are already divided by their colour pass: a second division by the
    // albedo would remodulate the light with the wrong colour. A filter that divides by it
    // itself (demodulates_itself) is given the light times its colour pass instead.
    if (filter->params().has("demodulate")) {
      if (filter->params().was_set("demodulate") && filter->params().get_bool("demodulate"))
        setup_notes_.push_back("demodulate=true has no effect with components=light_passes (each light pass is already "
                               "divided by its colour pass)");
      filter->set("demodulate", false);
    }
    filter->commit();
  }
  const std::size_t count = split ? light_stages().size() : 1;
  for (std::size_t i = 0; i < count; ++i) {
    auto stage = std::make_unique<Stage>();
    if (i == 0) {
      stage->filter = std::move(filter);
    } else {
      stage->filter = same_filter(*stages_.front()->filter);
      stage->filter->commit();
    }
    stages_.push_back(std::move(stage));
  }
  const Filter& first = *stages_.front()->filter;
  if (filters_alpha(first.params()) && !first.info().deep_input)
    alpha_ = std::make_unique<Stage>();  // its filter made when a frame's alpha first needs it
}

PassNeeds Reconstruction::needs() const {
  PassNeeds n = filter().needs();
  if (accumulate_) {
    n.require(Role::Position, "accumulate");
    n.require(Role::Normal, "accumulate");
    n.use(Role::Motion);
  }
  if (light_passes())
    for (Role r : light_pass_roles()) n.require(r, "components=light_passes");
  return n;
}

Image Reconstruction::run(const Frame& frame, const ExecOptions& options, std::vector<ComponentImage>* components,
                          Image* alpha) {
  if (alpha) *alpha = Image();
  const std::lock_guard<std::mutex> lock(mutex_);
  notes_.clear();
  if (accumulate_ && !light_passes()) {
    Frame copy = frame;  // the accumulated colour replaces the copy's, not the caller's
    Image out = run_locked(copy, options, components);
    if (alpha) *alpha = run_alpha(copy, options);
    return out;
  }
  Image out = light_passes() ? run_components(frame, options, components) : filter().execute(frame, options);
  if (alpha) *alpha = run_alpha(frame, options);
  return out;
}

Image Reconstruction::run_in_place(Frame& frame, const ExecOptions& options, std::vector<ComponentImage>* components) {
  const std::lock_guard<std::mutex> lock(mutex_);
  notes_.clear();
  Image out = run_locked(frame, options, components);
  put_alpha(frame, run_alpha(frame, options));
  return out;
}

Image Reconstruction::run_locked(Frame& frame, const ExecOptions& options, std::vector<ComponentImage>* components) {
  if (light_passes()) return run_components(frame, options, components);
  if (accumulate_)  // accumulation's passes first: nothing is accumulated for a frame the filter refuses
    check_passes(needs(), frame, "filter '" + filter().info().name + "' with accumulation");
  return run_stage(*stages_.front(), frame, options);
}

Image Reconstruction::run_alpha(const Frame& frame, const ExecOptions& options) {
  if (!alpha_) return {};
  const std::string why = alpha_kept_because(filter().params(), frame);
  if (!why.empty()) {
    if (std::string n = alpha_kept_note(frame, why); !n.empty()) notes_.push_back(std::move(n));
    alpha_->accumulator.reset();  // its history would skip this frame
    if (alpha_->filter) alpha_->filter->reset();
    return {};
  }
  alpha_filter();
  Frame grey = alpha_frame(frame);
  const AlphaRange range = alpha_range(frame.image(Role::Alpha));
  PartialCoverage coverage(frame.width, frame.height);
  coverage.mark(frame, 0);
  const std::size_t before = notes_.size();
  const Image filtered = run_stage(*alpha_, grey, options);
  // grey's colour now holds the alpha the filter read: the frame's, or its accumulation.
  std::size_t kept = 0;
  Image alpha = finish_alpha(filtered, grey.image(Role::Colour), coverage, range, options.nthreads, &kept);
  for (std::size_t k = before; k < notes_.size(); ++k) notes_[k] = "alpha: " + notes_[k];
  notes_.push_back(alpha_note(*alpha_->filter, range, kept));
  for (const std::string& m : alpha_->filter->notes()) notes_.push_back("alpha: " + m);
  return alpha;
}

Image Reconstruction::run_stage(Stage& stage, Frame& frame, const ExecOptions& options) {
  if (!accumulate_) return stage.filter->execute(frame, options);
  Image& colour = frame.passes[std::size_t(&frame.get(Role::Colour) - frame.passes.data())].image;
  const Image rgb = colour.channels() == 3 ? Image() : colour.channel_range(0, 3);
  const Image& signal = colour.channels() == 3 ? colour : rgb;
  classify_surfaces(frame, options.nthreads, stage.classes);
  HistoryGuardSettings hgs;
  // Ahead of a spatial filter a mirror keeps half-weight history, cut to its 3x3
  // neighbourhood (bmfr keeps none: its mirrors see no spatial filter but its TAA). 0.5
  // and 1 were level on the anim and metal samples; 0.5 keeps more of what was rendered.
  hgs.mirror_alpha = 0.5;
  stage.accumulator.set_guards(stage.guards.build(signal, stage.classes, hgs, options.nthreads));
  const Image& acc = stage.accumulator.accumulate(frame, signal, options.nthreads);
  stage.accumulator.clear_guards();
  if (stage.classes.mirror)
    notes_.push_back("accumulation: " + std::to_string(stage.classes.mirror) +
                     " mirror-like pixels (Glossy Color > 10x Diffuse Color) keep a half-weight history, no brighter "
                     "than their 3x3 neighbourhood");
  const std::size_t ch = std::size_t(colour.channels());
  for (std::size_t i = 0; i < acc.pixel_count(); ++i)
    for (std::size_t c = 0; c < 3; ++c) colour.data()[i * ch + c] = acc.data()[i * 3 + c];
  if (stage.classes.background)
    notes_.push_back("accumulation: " + std::to_string(stage.classes.background) +
                     " background pixels (normal 0: the world, which Blender gives no motion) keep no history "
                     "brighter than their 3x3 neighbourhood");
  if (stage.accumulator.last_reprojection().cut) notes_.push_back("accumulation: camera cut, history restarted");
  return stage.filter->execute(frame, options);
}

Image Reconstruction::run_components(const Frame& frame, const ExecOptions& options,
                                     std::vector<ComponentImage>* components) {
  // Every pass first (the light passes, then the filter's and accumulation's on the beauty
  // frame): no component's history moves for a frame another component would refuse.
  check_light_passes(frame);
  check_passes(needs(), frame,
               "filter '" + filter().info().name + "'" + (accumulate_ ? " with accumulation" : "") +
                   " with components=light_passes");
  const auto& comps = light_components();
  const auto& parts = light_stages();
  std::vector<Image> filtered(comps.size());
  const bool remodulated = filter().demodulates_itself();
  for (std::size_t i = 0; i < parts.size(); ++i) {
    const LightStage& s = parts[i];
    Frame part = component_frame(frame, comps[s.component], options.nthreads, s.part, remodulated);
    const std::size_t before = notes_.size();
    Image light = run_stage(*stages_[i], part, options);
    Image& sum = filtered[s.component];
    if (sum.pixel_count() == 0)
      sum = std::move(light);
    else
      add_light(sum, light, options.nthreads);
    const std::string name = light_stage_name(s);
    for (std::size_t k = before; k < notes_.size(); ++k) notes_[k] = name + ": " + notes_[k];
    for (const std::string& m : stages_[i]->filter->notes()) notes_.push_back(name + ": " + m);
  }
  Recombined r = recombine(frame, filtered, options.nthreads, remodulated);
  notes_.push_back(std::string("components=light_passes: diffuse light (direct + indirect), glossy and transmission "
                               "light (direct and indirect apart, then added) filtered one by one ") +
                   (remodulated ? "times their colour pass, which the filter divides by and multiplies back"
                                : "and multiplied by their colour pass") +
                   "; emission and environment passed through");
  if (components) *components = std::move(r.layers);
  return std::move(r.beauty);
}

void Reconstruction::reset() {
  const std::lock_guard<std::mutex> lock(mutex_);
  for (auto& stage : stages_) {
    stage->accumulator.reset();
    stage->filter->reset();
  }
  if (alpha_) {
    alpha_->accumulator.reset();
    if (alpha_->filter) alpha_->filter->reset();
  }
}

std::vector<std::string> Reconstruction::notes() const {
  const std::lock_guard<std::mutex> lock(mutex_);
  std::vector<std::string> all = filter().unused_settings();
  all.insert(all.end(), setup_notes_.begin(), setup_notes_.end());
  if (!light_passes()) all.insert(all.end(), filter().notes().begin(), filter().notes().end());
  all.insert(all.end(), notes_.begin(), notes_.end());
  return all;
}

std::vector<StageChoice> Reconstruction::choices() const {
  const std::lock_guard<std::mutex> lock(mutex_);
  std::vector<StageChoice> c;
  for (std::size_t i = 0; i < stages_.size(); ++i) {
    const auto* a = dynamic_cast<const AutoFilter*>(stages_[i]->filter.get());
    if (!a || a->chosen().empty()) continue;  // not auto, or not run yet
    c.push_back({light_passes() ? light_stage_name(light_stages()[i]) : "beauty", a->chosen()});
  }
  return c;
}

std::string choices_text(const std::vector<StageChoice>& choices) {
  if (choices.size() == 1 && choices.front().stage == "beauty") return choices.front().filter;
  std::string t;
  for (const StageChoice& c : choices) t += (t.empty() ? "" : "; ") + c.stage + "=" + c.filter;
  return t;
}

std::string notes_text(const std::vector<std::string>& notes) {
  std::string text;
  for (const std::string& n : notes) text += (text.empty() ? "" : "; ") + n;
  return text;
}

std::vector<std::pair<std::string, std::string>> run_attributes(const std::string& filter, const std::string& params,
                                                                const std::string& chosen, const std::string& notes) {
  std::vector<std::pair<std::string, std::string>> a = {{"mcreconFilter", filter}, {"mcreconParameters", params}};
  if (!chosen.empty()) a.emplace_back("mcreconChosen", chosen);
  if (!notes.empty()) a.emplace_back("mcreconNotes", notes);
  return a;
}

std::string Reconstruction::parameters_text() const {
  const std::string own = mcr::parameters_text(filter());
  return accumulate_ ? "accumulate=true " + own : own;
}

}  // namespace mcr
