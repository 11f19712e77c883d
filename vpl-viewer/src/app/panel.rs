//! The control panel and the view beside it.

use super::*;

impl State {
    pub(super) fn ui(&mut self, ctx: &egui::Context) {
        egui::SidePanel::left("controls").resizable(false).exact_width(PANEL_WIDTH).show(ctx, |ui| {
            egui::ScrollArea::vertical().show(ui, |ui| self.panel(ui));
        });
        egui::CentralPanel::default().frame(egui::Frame::NONE.fill(egui::Color32::BLACK)).show(ctx, |ui| self.view(ui));
    }

    pub(super) fn sampler_combo(ui: &mut egui::Ui, id: &str, names: &[String], value: &mut String) -> bool {
        let before = value.clone();
        egui::ComboBox::from_id_salt(id).selected_text(value.as_str()).show_ui(ui, |ui| {
            for n in names {
                ui.selectable_value(value, n.clone(), n.as_str());
            }
        });
        *value != before
    }

    pub(super) fn panel(&mut self, ui: &mut egui::Ui) {
        ui.heading(format!("vpl view: {}", self.world.scene_name));
        ui.label(&self.report.renderer_line);
        let res = self.resolution();
        ui.label(format!("render {}×{} (scale {:.2} of the view)", res.0, res.1, self.shown.scale));
        ui.separator();
        ui.horizontal(|ui| {
            ui.label("light");
            for (m, name) in [(Mode::Full, "full"), (Mode::Direct, "direct"), (Mode::Indirect, "indirect")] {
                if ui.selectable_label(self.shown.mode == m, name).clicked() && self.shown.mode != m {
                    self.shown.mode = m;
                    self.changed(true);
                }
            }
        });
        ui.horizontal(|ui| {
            let mut v = self.shown.vpls;
            ui.label("VPLs");
            ui.add(egui::DragValue::new(&mut v).range(1..=65536));
            if v != self.shown.vpls {
                self.shown.vpls = v;
                self.changed(true);
            }
            let mut s = self.shown.scale;
            ui.label("scale");
            ui.add(egui::DragValue::new(&mut s).range(0.05..=1.0).speed(0.01));
            if s != self.shown.scale {
                self.shown.scale = s;
                self.changed(true);
            }
        });
        ui.horizontal(|ui| {
            ui.label(if self.shown.split { "left" } else { "sampler" });
            if Self::sampler_combo(ui, "left", &self.world.names, &mut self.shown.sides[0]) {
                self.changed(true);
            }
        });
        ui.horizontal(|ui| {
            if ui.checkbox(&mut self.shown.split, "split, right").changed() {
                self.changed(true);
            }
            if self.shown.split && Self::sampler_combo(ui, "right", &self.world.names, &mut self.shown.sides[1]) {
                self.changed(true);
            }
        });
        ui.horizontal(|ui| {
            ui.label("overlay");
            for (o, name) in [(Overlay::Off, "off"), (Overlay::Vpls, "VPLs"), (Overlay::Interleave, "interleaving")] {
                if ui.selectable_label(self.shown.overlay == o, name).clicked() {
                    self.shown.overlay = o;
                    self.picture.recompose = true;
                }
            }
        });
        ui.label(
            egui::RichText::new(match self.shown.overlay {
                Overlay::Off => "click a VPL (VPL overlay) to see its shadow map".to_string(),
                Overlay::Vpls => "colour: flux against the median (blue ¹⁄₁₀₀×, red 100×); white ring: moved this frame".into(),
                Overlay::Interleave => "pixel class 4·(y mod 4) + (x mod 4) shades with VPL subset c; a picked VPL lights its class".into(),
            })
            .small(),
        );
        if let Some(p) = self.pick()
            && let Some(v) = self.picture.last.get(p.side).and_then(|s| s.out.vpls.get(p.slot)).copied()
        {
            let sampler = self.picture.last[p.side].spec.sampler.clone();
            ui.horizontal(|ui| {
                ui.label(
                    egui::RichText::new(format!(
                        "VPL {} of {}: bounce {}, flux {:.3e}{}",
                        p.slot,
                        sampler,
                        v.bounce,
                        vpl_core::image::luminance(v.flux),
                        p.class.map_or(String::new(), |c| format!(", pixel class {c}"))
                    ))
                    .small(),
                );
                if ui.small_button("unpick").clicked() {
                    self.inspect.picked = None;
                    self.refresh_map();
                    self.picture.recompose = true;
                }
            });
        }
        ui.horizontal(|ui| {
            let mut on = self.inspect.reference_on;
            if ui.checkbox(&mut on, "reference (path tracer while still)").changed() {
                self.set_reference(on);
            }
        });
        if let Some(r) = &self.inspect.reference {
            let mut line = format!("reference: {} passes of 1 path per pixel", r.passes);
            for sd in &self.picture.last {
                if let Some((ratio, rmse)) = against_reference(&sd.out.image, &r.image) {
                    line.push_str(&format!(
                        "\n{}: mean {:.3}× the reference, RMS difference {:.3} of its mean",
                        sd.spec.sampler, ratio, rmse
                    ));
                }
            }
            ui.label(egui::RichText::new(line).small());
        }
        ui.horizontal(|ui| {
            ui.label("show");
            let before = self.shown.channel;
            egui::ComboBox::from_id_salt("channel").selected_text(self.shown.channel.name()).show_ui(ui, |ui| {
                for c in Channel::ALL {
                    ui.selectable_value(&mut self.shown.channel, c, c.name());
                }
            });
            ui.label("exposure");
            let e = self.shown.exposure;
            ui.add(egui::DragValue::new(&mut self.shown.exposure).range(0.01..=100.0).speed(0.05));
            if self.shown.channel != before || self.shown.exposure != e {
                self.picture.recompose = true;
            }
        });
        if self.anim.frame_count > 1 {
            ui.horizontal(|ui| {
                if ui.button(if self.anim.playing { "pause" } else { "play" }).clicked() {
                    self.anim.playing = !self.anim.playing;
                    if let Some(seq) = &self.world.setup.sequence {
                        self.anim.play_clock = self.anim.anim_frame as f64 / seq.fps as f64;
                    }
                }
                let mut f = self.anim.anim_frame;
                ui.add(egui::Slider::new(&mut f, 0..=self.anim.frame_count - 1).text("frame"));
                if f != self.anim.anim_frame {
                    self.anim.playing = false;
                    self.set_anim_frame(f);
                }
            });
            ui.checkbox(&mut self.anim.follow_camera, "camera follows the animation");
        }
        ui.separator();
        for s in &self.picture.last {
            let t = s.out.timings;
            ui.label(
                egui::RichText::new(format!(
                    "{}: {:.1} ms (G-buffer {:.1}, sampling {:.1}, visibility {:.1}, shading {:.1}, direct {:.1})\n{} stored, {} moved{}",
                    s.spec.sampler,
                    t.total_ms,
                    t.gbuffer_ms,
                    t.sampling_ms,
                    t.visibility_ms,
                    t.shading_ms,
                    t.direct_ms,
                    s.out.stored,
                    s.out.moved,
                    s.change.map_or(String::new(), |c| format!(", Σ|ΔL|/ΣL {c:.4}"))
                ))
                .small(),
            );
        }
        let names: Vec<String> = self.picture.last.iter().map(|s| s.spec.sampler.clone()).collect();
        let plot = |ui: &mut egui::Ui, id: &str, title: &str, columns: &[(usize, &str)], history: &[History; 2]| {
            ui.label(title);
            egui_plot::Plot::new(id)
                .height(80.0)
                .allow_drag(false)
                .allow_zoom(false)
                .allow_scroll(false)
                .include_y(0.0)
                .legend(egui_plot::Legend::default())
                .show(ui, |p| {
                    for (k, h) in history.iter().enumerate().take(names.len()) {
                        for (c, what) in columns {
                            let label =
                                if what.is_empty() || columns.len() == 1 { names[k].clone() } else { format!("{} {what}", names[k]) };
                            p.line(egui_plot::Line::new(label, h.series(*c)));
                        }
                    }
                });
        };
        let stages: Vec<(usize, &str)> = (1..=6).map(|c| (c, History::COLUMNS[c - 1])).collect();
        plot(ui, "ms", "milliseconds per stage", &stages, &self.picture.history);
        plot(ui, "moved", "VPLs moved per frame", &[(7, "")], &self.picture.history);
        plot(ui, "change", "frame-to-frame change Σ|ΔL|/ΣL", &[(8, "")], &self.picture.history);
        ui.separator();
        ui.horizontal(|ui| {
            if ui.button("screenshot (PNG, EXR)").clicked() {
                self.session.shots += 1;
                self.session.pending_shot = Some(PathBuf::from(format!("vpl-view-{}-{}", self.world.scene_name, self.session.shots)));
            }
            if self.rec.recording.is_none() {
                if ui.button("record path").clicked() {
                    self.record_start();
                }
            } else if ui.button("stop, write scene file").clicked() {
                self.rec.recordings += 1;
                let path = PathBuf::from(format!("vpl-view-{}-path-{}.toml", self.world.scene_name, self.rec.recordings));
                if let Err(e) = self.record_stop(&path) {
                    self.report.error_line = Some(e.to_string());
                }
            }
        });
        if let Some((start, r)) = &self.rec.recording {
            ui.label(egui::RichText::new(format!("recording: {:.1} s, {} keys", start.elapsed().as_secs_f32(), r.len())).small());
        }
        ui.label(
            egui::RichText::new("left drag: orbit · right drag: look · WASD QE: fly · wheel: dolly · Ctrl+drag: move the light").small(),
        );
        if let Some(s) = &self.report.status_line {
            ui.label(egui::RichText::new(s).small());
        }
        if let Some(e) = &self.report.error_line {
            ui.colored_label(egui::Color32::from_rgb(255, 90, 90), e);
        }
    }

    pub(super) fn view(&mut self, ui: &mut egui::Ui) {
        let rect = ui.available_rect_before_wrap();
        if self.picture.view_rect.is_none_or(|r| (r.size() - rect.size()).length() > 0.5) {
            let first = self.picture.view_rect.is_none();
            self.picture.view_rect = Some(rect);
            if !first {
                self.changed(true);
            }
        }
        let response = ui.allocate_rect(rect, egui::Sense::click_and_drag());
        match self.picture.view_texture {
            Some(t) => {
                ui.painter().image(t, rect, egui::Rect::from_min_max(egui::pos2(0.0, 0.0), egui::pos2(1.0, 1.0)), egui::Color32::WHITE);
            }
            None => {
                ui.painter().text(
                    rect.center(),
                    egui::Align2::CENTER_CENTER,
                    "rendering the first frame…",
                    egui::FontId::proportional(18.0),
                    egui::Color32::GRAY,
                );
            }
        }
        let d = response.drag_delta() * self.picture.pixels_per_point;
        if d != egui::Vec2::ZERO {
            let ctrl = ui.input(|i| i.modifiers.command);
            if response.dragged_by(egui::PointerButton::Primary) && ctrl {
                self.move_light(d.x, d.y);
            } else if response.dragged_by(egui::PointerButton::Primary) {
                self.world.cam.orbit(-d.x * 0.005, -d.y * 0.005);
                self.changed(false);
            } else if response.dragged_by(egui::PointerButton::Secondary) {
                self.world.cam.look(-d.x * 0.003, -d.y * 0.003);
                self.changed(false);
            }
        }
        // A click (no drag) picks the VPL nearest to it.
        if response.clicked()
            && let Some(pos) = response.interact_pointer_pos()
            && let Some((cw, ch)) = self.picture.composite.as_ref().map(|c| (c.width as f32, c.height as f32))
        {
            let x = (pos.x - rect.min.x) / rect.width().max(1.0) * cw;
            let y = (pos.y - rect.min.y) / rect.height().max(1.0) * ch;
            let radius = PICK_RADIUS * cw / (rect.width() * self.picture.pixels_per_point).max(1.0);
            self.pick_at(x, y, radius);
        }
        // The picked VPL's shadow map, in the view's lower right corner.
        self.inspect.map_rect = None;
        if let Some((_, m)) = &self.inspect.map {
            let texture = self.inspect.map_texture.get_or_insert_with(|| {
                let image = egui::ColorImage::from_rgba_unmultiplied([m.res as usize, m.res as usize], &m.rgba);
                ui.ctx().load_texture("vpl-view shadow map", image, egui::TextureOptions::NEAREST)
            });
            let side = (rect.height() * 0.4).min(rect.width() * 0.4).min(256.0);
            let inset = egui::Rect::from_min_size(rect.max - egui::vec2(side + 8.0, side + 8.0), egui::vec2(side, side));
            let uv = egui::Rect::from_min_max(egui::pos2(0.0, 0.0), egui::pos2(1.0, 1.0));
            ui.painter().image(texture.id(), inset, uv, egui::Color32::WHITE);
            ui.painter().rect_stroke(inset, 0.0, egui::Stroke::new(2.0, egui::Color32::from_rgb(255, 0, 255)), egui::StrokeKind::Outside);
            ui.painter().text(
                inset.left_top() - egui::vec2(0.0, 2.0),
                egui::Align2::LEFT_BOTTOM,
                format!("shadow map of VPL {} ({}², paraboloid)", self.inspect.picked.map_or(0, |p| p.1), m.res),
                egui::FontId::proportional(12.0),
                egui::Color32::from_rgb(255, 0, 255),
            );
            self.inspect.map_rect = Some(inset);
        }
        if response.hovered() {
            let scroll = ui.input(|i| i.smooth_scroll_delta.y);
            if scroll != 0.0 {
                self.world.cam.dolly(scroll * 0.002);
                self.changed(false);
            }
        }
    }
}
