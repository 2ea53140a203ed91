//! The lens's visibility mask as an OpenXR session keeps it, without the runtime calls
//! (those are `session/mask.rs`): each view's mask read through XR_KHR_visibility_mask
//! (its hidden triangle mesh, else its visible one), replaced when the runtime says a
//! view's mask changed (`XrEventDataVisibilityMaskChangedKHR`), or, where the runtime
//! offers no extension, Monado's default from each view's field of view (the four
//! corners cut off) following the field of view the frames are rendered with. Pure
//! bookkeeping, so the event path is tested without a runtime.
//!
//! Some Monado builds' in-process runtime crashes in `xrGetVisibilityMaskKHR` for a device
//! without a mask of its own, its simulated HMD among them: `xrt_device_get_visibility_mask`
//! calls the device's function pointer, which such a device leaves NULL. Upstream, the
//! interface came without a NULL check (69afb6274, 2023-11-08), got one with Monado's
//! default mask behind it (2639d830b, "Fixes crash bug in xrGetVisibilityMaskKHR for
//! in-process builds", 2024-05-15) and lost it again ("xrt: remove function pointer
//! check", 1473430ee, 2024-11-13; still so at the end of 2024). Monado's runtime name
//! carries its `git describe` ("Monado(XRT) by Collabora et al 'v24.0.0-2403-g59c34e17b'",
//! 59c34e17b4d9 being 33 commits after 1473430ee), which places a build: vrao does not
//! call it on the builds with the bug ([`monado_lacks_mask_check`]) and takes the default
//! Monado itself gives such a device; everywhere else (a device with a mask of its own
//! keeps it) it asks. [`MASK_VAR`] overrides the choice.

use glam::Vec2;
use vrao_ao::{Fov, ViewMask, VisibilityMask};
use vrao_render::scene::limits::Trouble;

/// Views of PRIMARY_STEREO: left, then right.
pub const VIEWS: usize = 2;

/// The source of a mask read from the runtime, for reports.
pub const RUNTIME_SOURCE: &str = "the OpenXR runtime (XR_KHR_visibility_mask)";

/// The most vertices or indices vrao takes from one of the runtime's meshes (three per
/// triangle of [`ViewMask::MAX_TRIANGLES`]): a larger count is refused, not allocated.
pub const MAX_MESH_ELEMENTS: usize = 3 * ViewMask::MAX_TRIANGLES;

/// One mesh as `xrGetVisibilityMaskKHR` returned it: vertices on the view's image plane
/// at z = −1 (the tangents of the view angles, x right, y up), three indices a triangle.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct MaskMesh {
    /// The vertices.
    pub vertices: Vec<Vec2>,
    /// The indices, three a triangle.
    pub indices: Vec<u32>,
}

impl MaskMesh {
    /// Whether the mesh has no triangle.
    pub fn is_empty(&self) -> bool {
        self.indices.len() < 3
    }
}

/// The environment variable that overrides where the mask comes from when the runtime
/// offers XR_KHR_visibility_mask: `runtime` reads it from the runtime whatever the
/// runtime is, `fov` takes Monado's default from the field of view instead.
pub const MASK_VAR: &str = "VRAO_OPENXR_VISIBILITY_MASK";

/// What [`MASK_VAR`] asks for.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum MaskChoice {
    /// The runtime's mask, whatever the runtime is (`runtime`).
    Runtime,
    /// Monado's default from the field of view, never the runtime's (`fov`).
    Fov,
}

impl MaskChoice {
    /// The choice a value of [`MASK_VAR`] names: unset or blank is `None` (vrao chooses);
    /// any other value than `runtime` or `fov` is refused, as `--mask` refuses one.
    pub fn parse(value: Option<&str>) -> Result<Option<MaskChoice>, Trouble> {
        match value.map(str::trim) {
            None | Some("") => Ok(None),
            Some("runtime") => Ok(Some(MaskChoice::Runtime)),
            Some("fov") => Ok(Some(MaskChoice::Fov)),
            Some(other) => Err(Trouble(format!("{MASK_VAR}={other} is neither `runtime` nor `fov` (or unset)"))),
        }
    }

    /// The choice the environment holds now ([`MaskChoice::parse`]); a value that is not
    /// UTF-8 is refused like any other unknown one.
    pub fn from_env() -> Result<Option<MaskChoice>, Trouble> {
        let value = std::env::var_os(MASK_VAR).map(|v| v.to_string_lossy().into_owned());
        MaskChoice::parse(value.as_deref())
    }
}

/// Commits after v24.0.0 at which Monado's NULL check was removed again (1473430ee):
/// 59c34e17b4d9, `v24.0.0-2403`, is 33 commits after it.
pub const MONADO_24_CHECK_REMOVED_AT: u32 = 2403 - 33;

/// Whether the Monado build `runtime_name` and `major` (XrInstanceProperties) name calls
/// the device's mask function without a NULL check (see the module comment):
/// - a v24 development build at or after [`MONADO_24_CHECK_REMOVED_AT`] commits;
/// - a v21 development build (the version Monado reported until June 2024, the mask
///   interface's first half year, without the check until May 2024; where in that span
///   a build lies its name does not tell reliably, so all of them);
/// - a build whose name carries no `git describe` but reports major 21 or 24 with a
///   suffix vrao cannot read.
///
/// Not the v24.0.0 release itself (tagged with the check in place), nor Monado 25 and
/// later, nor any other runtime.
pub fn monado_lacks_mask_check(runtime_name: &str, major: u16) -> bool {
    if !runtime_name.starts_with("Monado") {
        return false;
    }
    match (major, monado_commits_after_tag(runtime_name)) {
        (24, Some(Some(commits))) => commits >= MONADO_24_CHECK_REMOVED_AT,
        (24, Some(None)) => false,
        (21, Some(Some(_))) => true,
        (21 | 24, None) => true,
        _ => false,
    }
}

/// The commits after the release tag in a Monado runtime name's `git describe` ('vX.Y.Z',
/// 'vX.Y.Z-N-gHASH', either perhaps with '-dirty'): `Some(None)` for the tag itself,
/// `None` when the name has no such quoted description.
fn monado_commits_after_tag(runtime_name: &str) -> Option<Option<u32>> {
    let describe = runtime_name.split('\'').nth(1)?.strip_prefix('v')?;
    let mut parts = describe.split('-');
    let version = parts.next()?;
    if version.split('.').any(|n| n.parse::<u32>().is_err()) {
        return None;
    }
    match parts.next() {
        None | Some("dirty") => Some(None),
        Some(n) => n.parse().ok().map(Some),
    }
}

/// Why vrao does not call `xrGetVisibilityMaskKHR` on a runtime that offers the extension
/// (`None`: it does), from the runtime's name, its version's major number and the choice
/// [`MASK_VAR`] made: the Monado builds of [`monado_lacks_mask_check`].
pub fn skip_runtime_mask(runtime_name: &str, major: u16, choice: Option<MaskChoice>) -> Option<String> {
    match choice {
        Some(MaskChoice::Runtime) => None,
        Some(MaskChoice::Fov) => Some(format!("{MASK_VAR}=fov")),
        None if monado_lacks_mask_check(runtime_name, major) => Some(format!(
            "not read from this Monado {major} build: its in-process runtime crashes in xrGetVisibilityMaskKHR for a \
             device without a mask of its own, such as its simulated HMD, and gives such a device this one; \
             {MASK_VAR}=runtime reads it anyway"
        )),
        None => None,
    }
}

/// Refuses counts above [`MAX_MESH_ELEMENTS`] before anything is allocated for them.
pub fn check_counts(vertices: u32, indices: u32) -> Result<(), Trouble> {
    let (v, i) = (vertices as usize, indices as usize);
    if v > MAX_MESH_ELEMENTS || i > MAX_MESH_ELEMENTS {
        return Err(Trouble(format!(
            "the mesh has {v} vertices and {i} indices (vrao takes at most {MAX_MESH_ELEMENTS} of each)"
        )));
    }
    Ok(())
}

/// One view's mask from its hidden triangle mesh; an empty hidden mesh asks for the
/// visible one (`visible`, called only then). A failed read, both meshes empty, or a
/// mesh [`ViewMask`] refuses (indices out of range, a vertex that is not finite) is the
/// reason there is no mask.
pub fn view_mask(
    hidden: Result<MaskMesh, Trouble>,
    visible: impl FnOnce() -> Result<MaskMesh, Trouble>,
) -> Result<ViewMask, Trouble> {
    let hidden = hidden.map_err(|e| format!("hidden triangle mesh: {e}"))?;
    if !hidden.is_empty() {
        return ViewMask::from_hidden_mesh(&hidden.vertices, &hidden.indices, format!("{RUNTIME_SOURCE}, hidden mesh"))
            .map_err(|e| Trouble(format!("hidden triangle mesh: {e}")));
    }
    let visible = visible().map_err(|e| format!("the hidden triangle mesh is empty; visible triangle mesh: {e}"))?;
    if visible.is_empty() {
        return Err("the hidden and the visible triangle meshes are both empty".into());
    }
    ViewMask::from_visible_mesh(&visible.vertices, &visible.indices, format!("{RUNTIME_SOURCE}, visible mesh"))
        .map_err(|e| Trouble(format!("visible triangle mesh: {e}")))
}

/// Where the session's mask comes from.
#[derive(Clone, Debug, PartialEq)]
enum Origin {
    /// Read from the runtime (XR_KHR_visibility_mask), view by view.
    Runtime,
    /// Not from the runtime (`why`: it has no XR_KHR_visibility_mask, or vrao does not
    /// call it): Monado's default from the fields of view of the frames (`None` before
    /// the first frame).
    FieldOfView { why: String, built_for: Option<[Fov; VIEWS]> },
}

/// The session's visibility mask: one [`ViewMask`] per view, and the [`VisibilityMask`]
/// the headset hands out once every view has one.
#[derive(Clone, Debug, PartialEq)]
pub struct SessionMask {
    origin: Origin,
    views: [Option<ViewMask>; VIEWS],
    mask: Option<VisibilityMask>,
    /// Change events followed (the runtime's `XrEventDataVisibilityMaskChangedKHR`).
    changes: u64,
}

impl SessionMask {
    /// The mask read from the runtime at the start of the session, one read per view.
    /// Returns it and, when a view has no mask (the session then has none), one line
    /// saying why for the log.
    pub fn from_runtime(reads: [Result<ViewMask, Trouble>; VIEWS]) -> (SessionMask, Option<String>) {
        let mut problems = Vec::new();
        let views = reads.map(|read| read.map_err(|e| problems.push(e)).ok());
        let mut mask = SessionMask { origin: Origin::Runtime, views, mask: None, changes: 0 };
        mask.compose();
        let problem = (!problems.is_empty()).then(|| {
            let which: Vec<String> = mask
                .views
                .iter()
                .enumerate()
                .filter(|(_, v)| v.is_none())
                .zip(&problems)
                .map(|((i, _), why)| format!("view {i}: {why}"))
                .collect();
            format!("no visibility mask from the runtime ({}): every pixel is rendered", which.join("; "))
        });
        (mask, problem)
    }

    /// Not from the runtime (`why`, for the mask's source: the runtime has no
    /// XR_KHR_visibility_mask, or [`skip_runtime_mask`]'s reason): Monado's default mask
    /// from each view's field of view, built at the first frame
    /// ([`SessionMask::follow_fov`]).
    pub fn from_field_of_view(why: &str) -> SessionMask {
        let origin = Origin::FieldOfView { why: why.to_string(), built_for: None };
        SessionMask { origin, views: [None, None], mask: None, changes: 0 }
    }

    /// Whether the mask is read from the runtime (XR_KHR_visibility_mask).
    pub fn from_the_runtime(&self) -> bool {
        self.origin == Origin::Runtime
    }

    /// The fields of view a frame is rendered with. Without the extension the mask is
    /// Monado's default for them: built at the first frame and again whenever they change
    /// (by more than 1e-5 rad). Returns whether the mask changed. A mask read from the
    /// runtime does not follow the field of view (it is the runtime's own).
    pub fn follow_fov(&mut self, fovs: [Fov; VIEWS]) -> bool {
        let Origin::FieldOfView { why, built_for } = &mut self.origin else { return false };
        let same = |a: &Fov, b: &Fov| {
            [(a.left, b.left), (a.right, b.right), (a.up, b.up), (a.down, b.down)]
                .iter()
                .all(|(x, y)| (x - y).abs() <= 1e-5)
        };
        if built_for.is_some_and(|built| built.iter().zip(&fovs).all(|(a, b)| same(a, b))) {
            return false;
        }
        *built_for = Some(fovs);
        self.views = fovs.map(|fov| {
            let mut view = ViewMask::corner_cut(fov.tangents());
            view.source = format!("{} of the views the OpenXR runtime locates ({why})", view.source);
            Some(view)
        });
        self.compose();
        true
    }

    /// The runtime's `XrEventDataVisibilityMaskChangedKHR` for view `view_index` of the
    /// session's view configuration (`ours`: the event names PRIMARY_STEREO), with the
    /// view's mask read again since (`read`, called only for an event that applies).
    /// A fresh mask replaces the view's; a failed read leaves the view without one, and
    /// the session without a mask (rendering pixels the lens hides is safe, hiding ones
    /// it shows is not). Returns one line for the log.
    pub fn changed(&mut self, ours: bool, view_index: u32, read: impl FnOnce() -> Result<ViewMask, Trouble>) -> String {
        if !ours {
            return format!("visibility mask of view {view_index} of another view configuration changed: ignored");
        }
        if self.origin != Origin::Runtime {
            return format!(
                "visibility mask of view {view_index} changed, but vrao does not read the runtime's: ignored"
            );
        }
        let Some(slot) = self.views.get_mut(view_index as usize) else {
            return format!("visibility mask of view {view_index} changed: PRIMARY_STEREO has {VIEWS} views, ignored");
        };
        self.changes += 1;
        let line = match read() {
            Ok(view) => {
                *slot = Some(view);
                format!("visibility mask of view {view_index} changed: read again")
            }
            Err(why) => {
                *slot = None;
                format!(
                    "visibility mask of view {view_index} changed but could not be read ({why}): no mask from now on"
                )
            }
        };
        self.compose();
        line
    }

    /// The mask the headset hands out: every view's, or `None` while a view has none.
    pub fn mask(&self) -> Option<&VisibilityMask> {
        self.mask.as_ref()
    }

    /// Change events followed so far.
    pub fn changes(&self) -> u64 {
        self.changes
    }

    fn compose(&mut self) {
        self.mask = self
            .views
            .iter()
            .cloned()
            .collect::<Option<Vec<ViewMask>>>()
            .filter(|views| !views.iter().all(ViewMask::is_empty))
            .map(|views| VisibilityMask { views });
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Monado's default hidden mesh (`u_visibility_mask_get_default`) for a ±45° view:
    /// the four corner triangles, twelve vertices indexed in order.
    fn monado_hidden() -> MaskMesh {
        let corners = [
            (1.0, 0.75),
            (1.0, 1.0),
            (0.75, 1.0),
            (-1.0, 1.0),
            (-1.0, 0.75),
            (-0.75, 1.0),
            (-1.0, -0.75),
            (-1.0, -1.0),
            (-0.75, -1.0),
            (0.75, -1.0),
            (1.0, -1.0),
            (1.0, -0.75),
        ];
        MaskMesh { vertices: corners.iter().map(|&(x, y)| Vec2::new(x, y)).collect(), indices: (0..12).collect() }
    }

    /// A visible mesh: the centre square of the ±1 rectangle (half its width and height).
    fn centre_square() -> MaskMesh {
        let v = [(-0.5, -0.5), (0.5, -0.5), (0.5, 0.5), (-0.5, 0.5)];
        MaskMesh { vertices: v.iter().map(|&(x, y)| Vec2::new(x, y)).collect(), indices: vec![0, 1, 2, 0, 2, 3] }
    }

    const SQUARE: [f64; 4] = [-1.0, 1.0, 1.0, -1.0];
    const Q: f32 = std::f32::consts::FRAC_PI_4;
    const FOV45: Fov = Fov { left: -Q, right: Q, up: Q, down: -Q };

    fn read(mesh: MaskMesh) -> Result<ViewMask, Trouble> {
        view_mask(Ok(mesh), || panic!("the hidden mesh is not empty: no visible read"))
    }

    #[test]
    fn the_hidden_mesh_is_taken_and_an_empty_one_asks_for_the_visible_one() {
        let view = read(monado_hidden()).unwrap();
        assert!(view.source.contains("XR_KHR_visibility_mask"), "{}", view.source);
        let share = view.hidden_share(200, 200, SQUARE);
        assert!((share - 0.03125).abs() < 0.002, "Monado's corners: {share}");

        let view = view_mask(Ok(MaskMesh::default()), || Ok(centre_square())).unwrap();
        assert!(view.source.contains("visible mesh"), "{}", view.source);
        assert!((view.hidden_share(200, 200, SQUARE) - 0.75).abs() < 0.01);

        let both_empty = view_mask(Ok(MaskMesh::default()), || Ok(MaskMesh::default()));
        assert!(both_empty.unwrap_err().0.contains("both empty"));
        let failed = view_mask(Err("xrGetVisibilityMaskKHR: XR_ERROR_RUNTIME_FAILURE".into()), || unreachable!());
        assert!(failed.unwrap_err().0.contains("XR_ERROR_RUNTIME_FAILURE"));
        let bad = MaskMesh { vertices: vec![Vec2::ZERO; 3], indices: vec![0, 1, 7] };
        assert!(view_mask(Ok(bad), || unreachable!()).unwrap_err().0.contains("index 7"));
        assert!(check_counts(12, 12).is_ok());
        assert!(check_counts(u32::MAX, 12).is_err(), "a runtime's absurd count is refused before allocating");
    }

    #[test]
    fn a_view_the_runtime_cannot_give_leaves_the_session_without_a_mask() {
        let (mask, problem) = SessionMask::from_runtime([read(monado_hidden()), Ok(read(monado_hidden()).unwrap())]);
        assert_eq!(problem, None);
        assert_eq!(mask.mask().map(|m| m.views.len()), Some(2));
        assert!(mask.from_the_runtime());

        let (mask, problem) = SessionMask::from_runtime([read(monado_hidden()), Err("both empty".into())]);
        assert_eq!(mask.mask(), None);
        let problem = problem.unwrap();
        assert!(problem.contains("view 1: both empty") && !problem.contains("view 0"), "{problem}");
    }

    #[test]
    fn a_change_event_replaces_the_view_it_names_and_only_that_one() {
        let (mut mask, _) = SessionMask::from_runtime([read(monado_hidden()), read(monado_hidden())]);
        let before = mask.mask().cloned().unwrap();
        // The runtime narrows the right eye's lens: its visible mesh is now the centre square.
        let line = mask.changed(true, 1, || view_mask(Ok(MaskMesh::default()), || Ok(centre_square())));
        assert!(line.contains("view 1 changed: read again"), "{line}");
        let after = mask.mask().cloned().unwrap();
        assert_eq!(after.views[0], before.views[0], "the left eye's mask is kept");
        assert_ne!(after.views[1], before.views[1]);
        assert!((after.views[1].hidden_share(100, 100, SQUARE) - 0.75).abs() < 0.02);
        assert_eq!(mask.changes(), 1);

        // Another view configuration's event, or a view PRIMARY_STEREO does not have: nothing read.
        let unchanged = mask.mask().cloned();
        assert!(mask.changed(false, 0, || unreachable!()).contains("ignored"));
        assert!(mask.changed(true, 2, || unreachable!()).contains("ignored"));
        assert_eq!(mask.mask().cloned(), unchanged);
        assert_eq!(mask.changes(), 1);

        // The new mask cannot be read: no mask (never the stale one), until a later event gives it.
        let line = mask.changed(true, 0, || Err("xrGetVisibilityMaskKHR: XR_ERROR_SESSION_LOST".into()));
        assert!(line.contains("could not be read"), "{line}");
        assert_eq!(mask.mask(), None);
        mask.changed(true, 0, || read(monado_hidden()));
        assert_eq!(mask.mask().map(|m| m.views[0].clone()), Some(before.views[0].clone()));
        assert_eq!(mask.changes(), 3);
    }

    #[test]
    fn without_the_extension_the_mask_is_monados_default_following_the_field_of_view() {
        let mut mask = SessionMask::from_field_of_view("the OpenXR runtime offers no XR_KHR_visibility_mask");
        assert_eq!(mask.mask(), None, "nothing before the first frame's fields of view");
        assert!(mask.follow_fov([FOV45, FOV45]));
        let view = &mask.mask().unwrap().views[0];
        assert!(view.source.contains("offers no XR_KHR_visibility_mask"), "{}", view.source);
        // The same mask Monado's runtime gives for the same field of view.
        // At 60 pixels no pixel centre lies on a cut's edge (at 64 eight a corner would).
        let (ours, monados) = (view.coverage(60, 60, SQUARE), read(monado_hidden()).unwrap().coverage(60, 60, SQUARE));
        assert_eq!(ours.iter().zip(&monados).filter(|(a, b)| a != b).count(), 0);
        assert!(!mask.follow_fov([FOV45, FOV45]), "the same fields of view: unchanged");
        let wider = Fov { left: -0.9, ..FOV45 };
        assert!(mask.follow_fov([wider, FOV45]));
        assert!((mask.mask().unwrap().views[0].hidden_share(100, 100, wider.tangents()) - 0.03125).abs() < 0.003);
        // Change events do not apply to a mask the runtime did not give.
        assert!(mask.changed(true, 0, || unreachable!()).contains("does not read"));
        // A mask read from the runtime does not follow the field of view.
        let (mut runtime, _) = SessionMask::from_runtime([read(monado_hidden()), read(monado_hidden())]);
        assert!(!runtime.follow_fov([wider, wider]));
    }

    #[test]
    fn only_monado_builds_without_the_null_check_are_not_asked() {
        let monado = "Monado(XRT) by Collabora et al 'v24.0.0-2403-g59c34e17b'";
        let why = skip_runtime_mask(monado, 24, None).unwrap();
        assert!(why.contains("Monado 24") && why.contains(MASK_VAR), "{why}");
        assert_eq!(skip_runtime_mask(monado, 24, Some(MaskChoice::Runtime)), None);
        // 1473430ee itself and after lack the check; the builds before it and the
        // release tag have it, so a device with its own mask keeps it there.
        let build = |describe: &str| format!("Monado(XRT) by Collabora et al '{describe}'");
        assert!(monado_lacks_mask_check(&build("v24.0.0-2370-g1473430ee"), 24));
        assert!(monado_lacks_mask_check(&build("v24.0.0-2403-g59c34e17b-dirty"), 24));
        assert!(!monado_lacks_mask_check(&build("v24.0.0-2369-g31fdb0bcd"), 24), "the commit before the removal");
        assert!(!monado_lacks_mask_check(&build("v24.0.0-120-gabcdef012"), 24), "a summer 2024 build");
        assert!(!monado_lacks_mask_check(&build("v24.0.0"), 24), "the v24.0.0 release");
        assert_eq!(skip_runtime_mask(&build("v24.0.0"), 24, None), None);
        // Before June 2024 Monado said 21: the interface's first months had no check.
        assert!(monado_lacks_mask_check(&build("v21.0.0-4100-g69afb6274"), 21));
        assert!(!monado_lacks_mask_check(&build("v21.0.0"), 21), "the 2021 release has no mask interface");
        // A name vrao cannot read, from a version with the bug, is not asked.
        assert!(monado_lacks_mask_check("Monado(XRT) by Collabora et al 'something'", 24));
        assert!(monado_lacks_mask_check("Monado(XRT)", 24));
        assert!(!monado_lacks_mask_check(&build("v25.0.0-12-g0123456789"), 25), "a later Monado is asked");
        assert_eq!(skip_runtime_mask("SteamVR/OpenXR", 2, None), None);
        assert!(!monado_lacks_mask_check("SteamVR/OpenXR 'v24.0.0-2403-g59c34e17b'", 24), "only Monado");
        assert_eq!(
            skip_runtime_mask("SteamVR/OpenXR", 2, Some(MaskChoice::Fov)).as_deref(),
            Some("VRAO_OPENXR_VISIBILITY_MASK=fov")
        );
        assert_eq!(
            skip_runtime_mask(&build("v24.0.0"), 24, Some(MaskChoice::Fov)).as_deref(),
            Some("VRAO_OPENXR_VISIBILITY_MASK=fov")
        );
        // The reason ends up in the mask's source.
        let mut mask = SessionMask::from_field_of_view(&why);
        mask.follow_fov([FOV45, FOV45]);
        assert!(mask.mask().unwrap().views[1].source.contains("not read from this Monado 24 build"));
        assert!(!mask.from_the_runtime());
    }

    #[test]
    fn the_variable_is_runtime_fov_or_unset_and_anything_else_is_refused() {
        assert_eq!(MaskChoice::parse(None), Ok(None));
        assert_eq!(MaskChoice::parse(Some("  ")), Ok(None), "blank is unset");
        assert_eq!(MaskChoice::parse(Some("runtime")), Ok(Some(MaskChoice::Runtime)));
        assert_eq!(MaskChoice::parse(Some(" fov ")), Ok(Some(MaskChoice::Fov)));
        let refused = MaskChoice::parse(Some("bogus")).unwrap_err().to_string();
        assert_eq!(refused, "VRAO_OPENXR_VISIBILITY_MASK=bogus is neither `runtime` nor `fov` (or unset)");
    }

    #[test]
    fn masks_hiding_nothing_are_no_mask() {
        let nothing = || ViewMask::from_hidden_mesh(&[], &[], RUNTIME_SOURCE).map_err(|e| Trouble(e.to_string()));
        let (mask, problem) = SessionMask::from_runtime([nothing(), nothing()]);
        assert_eq!((mask.mask(), problem), (None, None));
    }
}
