//! Seeds of the named random streams: randomness derives from `(world
//! seed, name)` only, so the order of robots or terrains in a file changes nothing.

/// A 64-bit seed for the random stream named `name` under `world_seed`
/// (FNV-1a over the seed's bytes and the name): independent of file order.
pub fn stream_seed(world_seed: u64, name: &str) -> u64 {
    let mut h: u64 = 0xcbf2_9ce4_8422_2325;
    for b in world_seed.to_le_bytes().iter().chain(name.as_bytes()) {
        h ^= u64::from(*b);
        h = h.wrapping_mul(0x0000_0100_0000_01b3);
    }
    h
}
