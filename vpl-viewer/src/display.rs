//! Which window system to open the window on, decided from the environment
//! before any window-system library is loaded.
//!
//! winit tries Wayland first and X11 after it. Trying Wayland loads
//! `libwayland-client`, which prints its own complaints to stderr (for one,
//! `error: XDG_RUNTIME_DIR is invalid or not set in the environment.`) when
//! there is no compositor to reach; and with neither system reachable the
//! error winit returns names a source file of its own. So the viewer looks
//! first: it opens Wayland only where a Wayland socket can be named, X11
//! only where `DISPLAY` is set, and says "no display" in its own one line
//! otherwise, before it loads anything.

use std::path::Path;

/// A window system the environment names.
// Read on Linux alone (winit's backends are chosen there); tested everywhere.
#[cfg_attr(not(target_os = "linux"), allow(dead_code))]
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum WindowSystem {
    /// A Wayland compositor: `WAYLAND_SOCKET`, or the socket
    /// `WAYLAND_DISPLAY` names (absolute, or under `XDG_RUNTIME_DIR`;
    /// `wayland-0` when unset) exists.
    Wayland,
    /// An X server: `DISPLAY` is set.
    X11,
}

/// The window system to use, from the environment as `var` reads it and
/// the file system as `exists` sees it; `Err` says in words why there is
/// none. Wayland first where both are there, as winit orders them.
#[cfg_attr(not(target_os = "linux"), allow(dead_code))] // as WindowSystem
pub(crate) fn choose(var: impl Fn(&str) -> Option<String>, exists: impl Fn(&Path) -> bool) -> Result<WindowSystem, String> {
    let set = |name: &str| var(name).filter(|v| !v.is_empty());
    if set("WAYLAND_SOCKET").is_some() {
        return Ok(WindowSystem::Wayland);
    }
    let name = set("WAYLAND_DISPLAY");
    let socket = match &name {
        Some(n) if Path::new(n).is_absolute() => Some(Path::new(n).to_path_buf()),
        _ => set("XDG_RUNTIME_DIR").map(|dir| Path::new(&dir).join(name.as_deref().unwrap_or("wayland-0"))),
    };
    if socket.as_deref().is_some_and(&exists) {
        return Ok(WindowSystem::Wayland);
    }
    if set("DISPLAY").is_some() {
        return Ok(WindowSystem::X11);
    }
    Err(match name {
        Some(n) => format!("DISPLAY is not set and the Wayland socket `{n}` is not there"),
        None => "neither DISPLAY nor WAYLAND_DISPLAY is set".to_string(),
    })
}

/// [`choose`] over this process's environment and file system.
#[cfg_attr(not(target_os = "linux"), allow(dead_code))] // as WindowSystem
pub(crate) fn from_env() -> Result<WindowSystem, String> {
    choose(|name| std::env::var(name).ok(), |p| p.exists())
}

/// A window-system error in words: winit's `os error at FILE:LINE: reason`
/// loses the location inside winit's sources, which says nothing to a user.
pub(crate) fn reason(error: &dyn std::fmt::Display) -> String {
    let text = error.to_string();
    match text.strip_prefix("os error at ") {
        // The location is `path:line`; the reason follows the next ": ".
        Some(rest) => rest.split_once(": ").map_or(text.clone(), |(_, why)| why.to_string()),
        None => text,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::collections::HashMap;

    fn pick(vars: &[(&str, &str)], sockets: &[&str]) -> Result<WindowSystem, String> {
        let vars: HashMap<String, String> = vars.iter().map(|(k, v)| (k.to_string(), v.to_string())).collect();
        choose(|n| vars.get(n).cloned(), |p| sockets.iter().any(|s| Path::new(s) == p))
    }

    #[test]
    fn nothing_set_is_no_display_in_words() {
        let e = pick(&[], &[]).unwrap_err();
        assert!(e.contains("DISPLAY"), "{e}");
        // Empty values count as unset, as the libraries treat them.
        assert!(pick(&[("DISPLAY", ""), ("WAYLAND_DISPLAY", "")], &[]).is_err());
    }

    #[test]
    fn x11_where_only_display_is_set() {
        assert_eq!(pick(&[("DISPLAY", ":99")], &[]), Ok(WindowSystem::X11));
        // A runtime folder without a compositor's socket is not Wayland.
        assert_eq!(pick(&[("DISPLAY", ":99"), ("XDG_RUNTIME_DIR", "/run/user/7")], &[]), Ok(WindowSystem::X11));
    }

    #[test]
    fn wayland_only_where_its_socket_is_named_and_there() {
        let run = [("XDG_RUNTIME_DIR", "/run/user/7")];
        assert_eq!(pick(&run, &["/run/user/7/wayland-0"]), Ok(WindowSystem::Wayland));
        assert_eq!(pick(&[run[0], ("WAYLAND_DISPLAY", "wayland-1")], &["/run/user/7/wayland-1"]), Ok(WindowSystem::Wayland));
        assert_eq!(pick(&[("WAYLAND_DISPLAY", "/tmp/w")], &["/tmp/w"]), Ok(WindowSystem::Wayland));
        assert_eq!(pick(&[("WAYLAND_SOCKET", "5")], &[]), Ok(WindowSystem::Wayland));
        // Named but without a runtime folder: the case that made
        // libwayland print its own lines.
        let e = pick(&[("WAYLAND_DISPLAY", "wayland-1")], &["/run/user/7/wayland-1"]).unwrap_err();
        assert!(e.contains("wayland-1"), "{e}");
        assert_eq!(pick(&[("WAYLAND_DISPLAY", "wayland-1"), ("DISPLAY", ":0")], &[]), Ok(WindowSystem::X11));
    }

    #[test]
    fn winit_locations_are_left_out() {
        let e = "os error at /home/u/.cargo/registry/src/x/winit-0.30.13/src/platform_impl/linux/mod.rs:765: neither WAYLAND_DISPLAY nor DISPLAY is set";
        assert_eq!(reason(&e), "neither WAYLAND_DISPLAY nor DISPLAY is set");
        assert_eq!(reason(&"the surface was lost"), "the surface was lost");
    }
}
