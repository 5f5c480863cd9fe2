//! How `tassel demo` colours its level: a colour per level collider. The character's body
//! and colours are `tassel_gltf`'s ([`tassel_gltf::builtin_body`]).

/// Colour of a level collider, by its name's first word.
pub fn level_color(name: &str) -> [u8; 3] {
    match name.split(' ').next().unwrap_or("") {
        "floor" => [196, 198, 192],
        "stair" => [214, 196, 160],
        "ramp" => [170, 190, 214],
        "crate" => [196, 140, 80],
        "wall" => [214, 210, 196],
        "door" => [150, 100, 70],
        "platform" => [110, 180, 140],
        "pillar" => [220, 220, 228],
        _ => [160, 154, 144],
    }
}
