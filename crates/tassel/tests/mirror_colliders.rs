//! Mirrored colliders (`mirror = "x"` on a `[[collider]]`; KawaiiPhysics 1.21's mirrored
//! limits): the twin's bone found by its side marker or named, its offset and rotation by
//! KawaiiPhysics' rule — on a symmetric rest pose the twin is the source reflected across
//! the character's YZ plane, checked by hand here — and every chain naming the source
//! colliding with the twin.

use glam::{Quat, Vec3};
use tassel::collide::Shape;
use tassel::dynamics::RigSettings;
use tassel::{CharacterSim, Skeleton, Transform};

/// A symmetric body: arms out to both sides, the left one turned about Z, the right one
/// the left's mirror image (its rest rotation is the left's mirrored: M·R·M); a strand
/// held out forward above the right shoulder, which gravity swings down through where
/// the right arm's ball will be.
fn body(left: &str, right: &str) -> Skeleton {
    let turn = Quat::from_rotation_z(0.4) * Quat::from_rotation_x(0.3);
    let mirrored = Quat::from_xyzw(turn.x, -turn.y, -turn.z, turn.w);
    let names = vec![
        "root".to_string(),
        left.to_string(),
        right.to_string(),
        "strand_0".to_string(),
        "strand_1".to_string(),
        "strand_2".to_string(),
        "strand_3".to_string(),
    ];
    let parents = vec![
        None,
        Some(0),
        Some(0),
        Some(0),
        Some(3),
        Some(3 + 1),
        Some(5),
    ];
    let rest = vec![
        Transform::from_translation(Vec3::new(0.0, 1.0, 0.0)),
        Transform::from_translation_rotation(Vec3::new(-0.3, 0.3, 0.0), turn),
        Transform::from_translation_rotation(Vec3::new(0.3, 0.3, 0.0), mirrored),
        Transform::from_translation(Vec3::new(0.3, 0.5, 0.02)),
        Transform::from_translation(Vec3::new(0.0, 0.0, 0.12)),
        Transform::from_translation(Vec3::new(0.0, 0.0, 0.12)),
        Transform::from_translation(Vec3::new(0.0, 0.0, 0.12)),
    ];
    Skeleton::new(names, parents, rest).unwrap()
}

fn rig(text_colliders: &str) -> String {
    format!(
        "[[chain]]\nname = \"strand\"\nroot = \"strand_0\"\nradius = 0.01\nstiffness = 0.02\n\
         damping = 0.05\ncolliders = [\"ball\"]\ngravity = [0.0, -9.81, 0.0]\n\n{text_colliders}"
    )
}

const BALL: &str = "[[collider]]\nname = \"ball\"\nbone = \"arm_L\"\nshape = \"capsule\"\nradius = 0.06\n\
                    length = 0.1\noffset = [0.05, 0.1, 0.03]\nrotation = [0.2, 0.1, 0.3, 0.9273618]\n";

/// The placed colliders of a simulation at rest, in model space.
fn placed(sk: &Skeleton, text: &str) -> Vec<tassel::collide::PlacedCollider> {
    let rig = RigSettings::from_toml_str(text).unwrap();
    let mut sim = CharacterSim::new(sk.clone(), &rig).unwrap();
    sim.frame(sk.rest(), Transform::IDENTITY, 0.0).unwrap();
    sim.chain_state().placed_colliders().to_vec()
}

#[test]
fn the_twin_is_the_source_reflected_on_a_symmetric_body() {
    let sk = body("arm_L", "arm_R");
    let with = format!("{BALL}mirror = \"x\"\n");
    let colliders = placed(&sk, &rig(&with));
    assert_eq!(colliders.len(), 2, "the source and its twin");
    let (a, b) = (colliders[0].transform, colliders[1].transform);
    let m = |v: Vec3| Vec3::new(-v.x, v.y, v.z);
    assert!(
        (b.translation - m(a.translation)).length() < 1e-5,
        "twin at {}, the source mirrored {}",
        b.translation,
        m(a.translation)
    );
    // The capsule's axis (local +Y) mirrored too.
    let (axis_a, axis_b) = (a.rotation * Vec3::Y, b.rotation * Vec3::Y);
    assert!(
        (axis_b - m(axis_a)).length() < 1e-5,
        "twin axis {axis_b}, the source's mirrored {}",
        m(axis_a)
    );
    assert!(matches!(colliders[1].shape, Shape::Capsule { .. }));
}

#[test]
fn the_twin_bone_is_found_by_its_side_marker_or_named() {
    for (left, right) in [
        ("arm_L", "arm_R"),
        ("arm_l", "arm_r"),
        ("arm.L", "arm.R"),
        ("L_arm", "R_arm"),
        ("LeftArm", "RightArm"),
        ("mixamorig:LeftArm", "mixamorig:RightArm"),
    ] {
        let sk = body(left, right);
        let text = rig(&format!("{}mirror = \"x\"\n", BALL.replace("arm_L", left)));
        let colliders = placed(&sk, &text);
        assert_eq!(colliders.len(), 2, "{left}");
        // And from the right side back to the left.
        let text = rig(&format!("{}mirror = \"x\"\n", BALL.replace("arm_L", right)));
        assert_eq!(placed(&sk, &text).len(), 2, "{right}");
    }
    // Fox-style names with different numbers: named.
    let sk = body("b_LeftLeg01_015", "b_RightLeg01_019");
    let text = rig(&format!(
        "{}mirror = \"x\"\nmirror_bone = \"b_RightLeg01_019\"\n",
        BALL.replace("arm_L", "b_LeftLeg01_015")
    ));
    assert_eq!(placed(&sk, &text).len(), 2);
}

#[test]
fn a_twin_that_cannot_be_made_is_refused_by_name() {
    let sk = body("arm_L", "arm_R");
    let cases = [
        (BALL.replace("arm_L", "root") + "mirror = \"x\"\n", "no bone mirrors 'root'"),
        (BALL.to_string() + "mirror = \"x\"\nmirror_bone = \"arm_L\"\n", "its own mirror"),
        (BALL.to_string() + "mirror = \"x\"\nmirror_bone = \"arm_X\"\n", "arm_X"),
        (
            BALL.to_string()
                + "mirror = \"x\"\n\n[[collider]]\nname = \"ball_mirror\"\nbone = \"root\"\nshape = \"sphere\"\nradius = 0.1\n",
            "ball_mirror",
        ),
        (BALL.to_string() + "mirror = \"w\"\n", "mirror"),
    ];
    for (colliders, named) in cases {
        let e = RigSettings::from_toml_str(&rig(&colliders))
            .and_then(|r| CharacterSim::new(sk.clone(), &r).map(|_| ()))
            .unwrap_err()
            .to_string();
        assert!(e.contains(named), "{named}: {e}");
    }
}

/// The strand names only the left arm's ball; with the mirror it also collides with the
/// right arm's twin: it falls onto it as onto the same ball written by hand where the
/// twin is (on the root bone, at the left ball's centre reflected), and past it without.
#[test]
fn a_chain_naming_the_source_collides_with_the_twin() {
    let sk = body("arm_L", "arm_R");
    // The left ball's centre 5 cm below the left arm and 2 cm forward (in the arm's turned
    // frame: offset = R⁻¹ · that), so its mirror sits beside the hanging strand.
    let turn = Quat::from_rotation_z(0.4) * Quat::from_rotation_x(0.3);
    let o = turn.inverse() * Vec3::new(0.0, -0.05, 0.02);
    let sphere = |name: &str, bone: &str, o: Vec3| {
        format!(
            "[[collider]]\nname = \"{name}\"\nbone = \"{bone}\"\nshape = \"sphere\"\n\
             radius = 0.08\noffset = [{}, {}, {}]\n",
            o.x, o.y, o.z
        )
    };
    let ball = sphere("ball", "arm_L", o);
    // The twin by hand: the left centre (-0.3, 1.25, 0.02) reflected, from the root at
    // (0, 1, 0).
    let by_hand = sphere("right", "root", Vec3::new(0.3, 0.25, 0.02));
    let run = |text: &str| {
        let rig = RigSettings::from_toml_str(text).unwrap();
        let mut sim = CharacterSim::new(sk.clone(), &rig).unwrap();
        let rest = sk.rest().to_vec();
        let mut path = Vec::new();
        for f in 0..120 {
            let dt = if f == 0 { 0.0 } else { 1.0 / 60.0 };
            // The body sways so the strand swings into the ball.
            let at =
                Transform::from_translation(Vec3::new(0.25 * (f as f32 * 0.08).sin(), 0.0, 0.0));
            sim.frame(&rest, at, dt).unwrap();
            path.extend((4..=6).map(|j| sim.pose().models[j].translation));
        }
        path
    };
    let gap = |a: &[Vec3], b: &[Vec3]| {
        a.iter()
            .zip(b)
            .map(|(x, y)| (*x - *y).length())
            .fold(0.0f32, f32::max)
    };
    let mirrored = run(&rig(&format!("{ball}mirror = \"x\"\n")));
    let hand =
        run(&rig(&format!("{ball}\n{by_hand}")).replace("[\"ball\"]", "[\"ball\", \"right\"]"));
    let neither = run(&rig(&ball));
    // The contacts amplify rounding: the hand-written ball moved by 1 µm, for scale.
    let nudged = sphere("right", "root", Vec3::new(0.300001, 0.25, 0.02));
    let hand_nudged =
        run(&rig(&format!("{ball}\n{nudged}")).replace("[\"ball\"]", "[\"ball\", \"right\"]"));
    let noise = gap(&hand, &hand_nudged);
    let (same, apart) = (gap(&mirrored, &hand), gap(&mirrored, &neither));
    println!(
        "the mirrored twin against the hand-written one: {same:.2e} m (the hand-written one \
         moved 1 µm: {noise:.2e} m); without a twin: {apart:.3} m"
    );
    assert!(
        same <= 2e-5_f32.max(4.0 * noise),
        "{same} (1 µm moves it {noise})"
    );
    assert!(apart > 1e-2, "the twin changes nothing: {apart}");
}
