//! Lane helpers for loops meant to vectorise.

/// `a` where `flag` is 1, `b` where it is 0, bit for bit. The compiler
/// turns `if` chains over several columns into branches, which keep a loop
/// scalar (and are mispredicted on random signs); this stays a blend.
#[inline(always)]
pub(crate) fn select(flag: u32, a: f32, b: f32) -> f32 {
    let m = flag.wrapping_neg();
    f32::from_bits((a.to_bits() & m) | (b.to_bits() & !m))
}

#[cfg(test)]
mod tests {
    use super::select;

    #[test]
    fn select_keeps_every_bit_of_the_chosen_lane() {
        for (a, b) in [
            (1.5f32, -2.0f32),
            (f32::NAN, 0.0),
            (-0.0, 0.0),
            (f32::INFINITY, 1e-40),
        ] {
            assert_eq!(select(1, a, b).to_bits(), a.to_bits());
            assert_eq!(select(0, a, b).to_bits(), b.to_bits());
        }
    }
}
