//! Scripted sessions: what a person would do at the window, as lines of a
//! file, so the viewer runs without anyone at it (CI under Xvfb, figures
//! for a paper made the same way twice).
//!
//! ```text
//! # a comment
//! frames 3            # wait until 3 more frames of every side are shown
//! sampler smc         # the sampler of the left (or only) side
//! split mir           # split view: mir on the right ("split off" ends it)
//! overlay vpls        # VPL splats, "interleave" (the pattern) or "off"
//! show normals        # image, reference, difference, albedo, normals, depth
//! reference on        # accumulate the path tracer while still ("off")
//! pick 0.5 0.4        # pick the VPL nearest this point of the view (0–1
//!                     # across, 0–1 down): ringed, its shadow map shown
//! pick off            # nothing picked
//! record start        # record the camera-and-light path …
//! record stop a.toml  # … and write it as a scene file with an animation
//! mode indirect       # full, direct or indirect light
//! vpls 512            # VPL budget of both sides
//! orbit 30 -10        # orbit the camera (degrees of yaw and pitch)
//! screenshot shots/a  # shots/a.png (the window), .exr (the view), .json
//! quit                # the session ends here (also at the end of the file)
//! ```

use crate::view::{Channel, Overlay};
use std::path::PathBuf;
use vpl_core::Mode;

/// One step of a scripted session.
#[derive(Clone, Debug, PartialEq)]
pub enum Step {
    /// Wait until this many more frames of every side are shown.
    Frames(u32),
    /// The sampler of the left (or only) side.
    Sampler(String),
    /// Split view with this sampler on the right; `None` ends it.
    Split(Option<String>),
    /// The overlay drawn over the view.
    Overlay(Overlay),
    /// The image or a G-buffer channel.
    Show(Channel),
    /// Which light paths the frames include.
    Mode(Mode),
    /// VPL budget of both sides.
    Vpls(usize),
    /// Orbit the camera by yaw and pitch, in degrees.
    Orbit(f32, f32),
    /// Accumulate the reference while the camera stands still, or stop.
    Reference(bool),
    /// Pick the visible VPL nearest a point of the view given as fractions
    /// of its width and height; `None` picks none.
    Pick(Option<(f32, f32)>),
    /// Start recording the camera-and-light path.
    RecordStart,
    /// Stop recording and write the scene file with the path as its animation.
    RecordStop(PathBuf),
    /// Write a screenshot: `PATH.png` (the window), `PATH.exr` (the view's
    /// radiance), `PATH.json` (where the view and the split lie in the PNG).
    Screenshot(PathBuf),
    /// End the session.
    Quit,
}

/// A line of a script that does not parse.
#[derive(Debug, thiserror::Error)]
#[error("script line {line}: {message}")]
pub struct ScriptError {
    /// 1-based line number.
    pub line: usize,
    /// What is wrong with it.
    pub message: String,
}

/// A parsed script.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Script {
    /// The steps, in order.
    pub steps: Vec<Step>,
}

impl Script {
    /// Parses a script (the format in the module's documentation). Sampler
    /// names are checked when the step runs, against the viewer's registry.
    pub fn parse(text: &str) -> Result<Script, ScriptError> {
        let mut steps = Vec::new();
        for (i, raw) in text.lines().enumerate() {
            let line = raw.split('#').next().unwrap_or("").trim();
            if line.is_empty() {
                continue;
            }
            let err = |message: String| ScriptError { line: i + 1, message };
            let mut words = line.split_whitespace();
            let verb = words.next().unwrap_or("");
            let args: Vec<&str> = words.collect();
            let one = || match args.as_slice() {
                [a] => Ok(*a),
                _ => Err(err(format!("`{verb}` takes one argument, got {}", args.len()))),
            };
            let step = match verb {
                "frames" => Step::Frames(one()?.parse().map_err(|_| err(format!("`frames` takes a count, got `{}`", args[0])))?),
                "sampler" => Step::Sampler(one()?.to_string()),
                "split" => Step::Split(Some(one()?).filter(|s| *s != "off").map(str::to_string)),
                "overlay" => Step::Overlay(
                    Overlay::parse(one()?).ok_or_else(|| err(format!("unknown overlay `{}` (vpls, interleave, off)", args[0])))?,
                ),
                "show" => {
                    Step::Show(Channel::parse(one()?).ok_or_else(|| {
                        err(format!("unknown channel `{}` (image, reference, difference, albedo, normals, depth)", args[0]))
                    })?)
                }
                "reference" => Step::Reference(match one()? {
                    "on" => true,
                    "off" => false,
                    o => return Err(err(format!("`reference` takes on or off, got `{o}`"))),
                }),
                "pick" => match args.as_slice() {
                    ["off"] => Step::Pick(None),
                    [a, b] => match (a.parse::<f32>(), b.parse::<f32>()) {
                        (Ok(a), Ok(b)) if (0.0..=1.0).contains(&a) && (0.0..=1.0).contains(&b) => Step::Pick(Some((a, b))),
                        _ => return Err(err(format!("`pick` takes two fractions of the view in [0, 1], got `{a} {b}`"))),
                    },
                    _ => return Err(err("`pick` takes two fractions of the view (across down) or off".into())),
                },
                "record" => match args.as_slice() {
                    ["start"] => Step::RecordStart,
                    ["stop", path] => Step::RecordStop(PathBuf::from(path)),
                    _ => return Err(err("`record` takes start, or stop and the scene file to write".into())),
                },
                "mode" => Step::Mode(match one()? {
                    "full" => Mode::Full,
                    "direct" => Mode::Direct,
                    "indirect" => Mode::Indirect,
                    m => return Err(err(format!("unknown mode `{m}` (full, direct, indirect)"))),
                }),
                "vpls" => Step::Vpls(match one()?.parse() {
                    Ok(n) if n > 0 => n,
                    _ => return Err(err(format!("`vpls` takes a positive count, got `{}`", args[0]))),
                }),
                "orbit" => match args.as_slice() {
                    [a, b] => match (a.parse::<f32>(), b.parse::<f32>()) {
                        (Ok(a), Ok(b)) if a.is_finite() && b.is_finite() => Step::Orbit(a, b),
                        _ => return Err(err(format!("`orbit` takes two angles in degrees, got `{a} {b}`"))),
                    },
                    _ => return Err(err(format!("`orbit` takes two angles (yaw pitch), got {}", args.len()))),
                },
                "screenshot" => Step::Screenshot(PathBuf::from(one()?)),
                "quit" => Step::Quit,
                v => {
                    return Err(err(format!(
                        "unknown command `{v}` (frames, sampler, split, overlay, show, mode, vpls, orbit, reference, pick, record, screenshot, quit)"
                    )));
                }
            };
            steps.push(step);
        }
        Ok(Script { steps })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parses_every_command() {
        let s = Script::parse(
            "# a session\nframes 2\nsampler smc\nsplit mir # right\nsplit off\noverlay vpls\nshow depth\nmode indirect\nvpls 64\norbit 30 -10\nreference on\noverlay interleave\nshow difference\npick 0.5 0.25\npick off\nrecord start\nrecord stop p.toml\nscreenshot a/b\n\nquit\n",
        )
        .unwrap();
        assert_eq!(
            s.steps,
            vec![
                Step::Frames(2),
                Step::Sampler("smc".into()),
                Step::Split(Some("mir".into())),
                Step::Split(None),
                Step::Overlay(Overlay::Vpls),
                Step::Show(Channel::Depth),
                Step::Mode(Mode::Indirect),
                Step::Vpls(64),
                Step::Orbit(30.0, -10.0),
                Step::Reference(true),
                Step::Overlay(Overlay::Interleave),
                Step::Show(Channel::Difference),
                Step::Pick(Some((0.5, 0.25))),
                Step::Pick(None),
                Step::RecordStart,
                Step::RecordStop("p.toml".into()),
                Step::Screenshot("a/b".into()),
                Step::Quit,
            ]
        );
    }

    #[test]
    fn bad_lines_name_their_number() {
        for (text, line) in [
            ("frames x", 1),
            ("frames 1\nfly 3", 2),
            ("\n\nvpls 0", 3),
            ("orbit 1", 1),
            ("show x", 1),
            ("sampler", 1),
            ("orbit nan 1", 1),
            ("pick 2 0", 1),
            ("record stop", 1),
            ("reference maybe", 1),
        ] {
            let e = Script::parse(text).unwrap_err();
            assert_eq!(e.line, line, "{text}: {e}");
        }
    }
}
