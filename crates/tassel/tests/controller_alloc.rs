//! The controller allocates nothing per call once its buffers have grown: every heap
//! allocation of the test's thread is counted (a global allocator that counts, then hands
//! over to the system's; the test harness's other threads allocate when they will — a CI
//! run once saw 4 of theirs — and the controller runs on the caller's thread), across the three cases of the criterion bench in the
//! 1 000-collider level and a moving platform. `move_shape_into` gives what `move_shape`
//! gives.

// A counting global allocator needs `unsafe impl GlobalAlloc`; it only forwards to the
// system allocator (see the SAFETY comment). Test code only.
#![allow(unsafe_code)]

use glam::{Quat, Vec3};
use std::alloc::{GlobalAlloc, Layout, System};
use std::cell::Cell;
use std::sync::atomic::{AtomicUsize, Ordering};
use tassel::builtin::level::{bench_level, bench_moves};
use tassel::controller::{CharacterCapsule, ControllerSettings, Level, Movement};
use tassel::Transform;

struct Counting;

static ALLOCATIONS: AtomicUsize = AtomicUsize::new(0);

thread_local! {
    /// Whether this thread's allocations are counted (a `const` cell: reading it never
    /// allocates).
    static COUNTED: Cell<bool> = const { Cell::new(false) };
}

fn count() {
    if COUNTED.try_with(Cell::get).unwrap_or(false) {
        ALLOCATIONS.fetch_add(1, Ordering::Relaxed);
    }
}

// SAFETY: every call is passed unchanged to the system allocator, which upholds the
// `GlobalAlloc` contract; the counter is an atomic add after a read of a `const`
// thread-local cell (which does not allocate).
unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        count();
        unsafe { System.alloc(layout) }
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        unsafe { System.dealloc(ptr, layout) }
    }
    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        count();
        unsafe { System.realloc(ptr, layout, new_size) }
    }
}

#[global_allocator]
static GLOBAL: Counting = Counting;

#[test]
fn move_shape_into_allocates_nothing_per_call() {
    COUNTED.with(|c| c.set(true));
    // The counter counts: this thread's allocation is seen.
    let probe = ALLOCATIONS.load(Ordering::Relaxed);
    drop(std::hint::black_box(vec![1u8; 64]));
    assert!(
        ALLOCATIONS.load(Ordering::Relaxed) > probe,
        "the counting allocator counts"
    );
    let mut level = Level::new(bench_level(1000, 7)).unwrap();
    let capsule = CharacterCapsule::with_height(1.7, 0.28);
    let s = ControllerSettings::default();
    let dt = 1.0 / 60.0;
    let centre_y = capsule.half_total_height() + s.skin;
    // The criterion bench's moves: flat, into the wall, climbing a riser.
    let cases = bench_moves(&level).unwrap().map(|(_, p, d)| (p, d));
    let mut out = Movement::default();
    // Warm up: the buffers grow to what these moves need.
    for (p, d) in &cases {
        s.move_shape_into(&level, &capsule, p, *d, dt, &mut out)
            .unwrap();
    }
    let before = ALLOCATIONS.load(Ordering::Relaxed);
    let mut checks = 0;
    for _ in 0..50 {
        for (p, d) in &cases {
            s.move_shape_into(&level, &capsule, p, *d, dt, &mut out)
                .unwrap();
            checks += out.hits.len() + out.stepped as usize;
        }
    }
    let during = ALLOCATIONS.load(Ordering::Relaxed) - before;
    assert_eq!(during, 0, "{during} allocations in 150 calls");
    // The cases do meet things (the wall and the riser), so the buffers were used.
    assert!(checks >= 100, "{checks}");
    for (p, d) in &cases {
        s.move_shape_into(&level, &capsule, p, *d, dt, &mut out)
            .unwrap();
        assert_eq!(out, s.move_shape(&level, &capsule, p, *d, dt).unwrap());
    }

    // Standing on a platform that moves and turns: carried, still no allocation.
    let platform = level
        .add(tassel::controller::LevelCollider::new(
            "platform",
            tassel::controller::LevelShape::Box {
                half_extents: Vec3::new(1.0, 0.1, 1.0),
            },
            Vec3::new(60.0, 0.1, 0.0),
        ))
        .unwrap();
    let mut centre = Vec3::new(60.0, 0.2 + centre_y, 0.0);
    let step = |level: &mut Level, k: usize| {
        level.start_frame();
        let t = k as f32 * dt;
        level
            .set_pose(
                platform,
                Vec3::new(60.0 + 0.5 * t, 0.1, 0.0),
                Quat::from_rotation_y(0.3 * t),
            )
            .unwrap();
    };
    let carry = |level: &Level, centre: &mut Vec3, out: &mut Movement| {
        let pose = Transform::from_translation(*centre);
        let before = ALLOCATIONS.load(Ordering::Relaxed);
        s.move_shape_into(level, &capsule, &pose, Vec3::ZERO, dt, out)
            .unwrap();
        *centre += out.translation;
        ALLOCATIONS.load(Ordering::Relaxed) - before
    };
    for k in 1..5 {
        step(&mut level, k);
        carry(&level, &mut centre, &mut out);
    }
    // Only the controller's calls are counted (moving the platform is the level's edit).
    let (mut during, mut carried) = (0, 0);
    for k in 5..65 {
        step(&mut level, k);
        during += carry(&level, &mut centre, &mut out);
        carried += out.platform.is_some() as usize;
    }
    assert_eq!(carried, 60, "not carried on every frame");
    assert_eq!(during, 0, "{during} allocations in 60 carried frames");
}
