//! `Skeleton::depth_first`: the order an outliner lists a joint hierarchy in, checked against
//! hand-drawn trees.

use glam::{Quat, Vec3};
use keyrig_core::{Joint, Skeleton};

fn skeleton(parents: &[Option<usize>]) -> Skeleton {
    Skeleton::new(
        parents
            .iter()
            .enumerate()
            .map(|(j, &p)| Joint::new(format!("j{j}"), p, Vec3::X, Quat::IDENTITY))
            .collect(),
    )
}

#[test]
fn children_follow_their_parent_in_index_order() {
    // 0 ─┬─ 1 ── 3 ── 4
    //    └─ 2
    // 5 (a second root) ── 6
    let s = skeleton(&[None, Some(0), Some(0), Some(1), Some(3), None, Some(5)]);
    assert_eq!(s.depth_first(), vec![(0, 0), (1, 1), (3, 2), (4, 3), (2, 1), (5, 0), (6, 1)]);
}

#[test]
fn a_parent_after_its_child_makes_the_child_a_root() {
    // Joint 1 names 2 as its parent and joint 2 names itself: both are walked as roots, in
    // index order, and every joint appears once.
    let s = skeleton(&[None, Some(2), Some(2), Some(0)]);
    assert_eq!(s.depth_first(), vec![(0, 0), (3, 1), (1, 0), (2, 0)]);
    assert_eq!(skeleton(&[]).depth_first(), Vec::new());
}

#[test]
fn a_deep_chain_is_walked_without_recursion() {
    let parents: Vec<Option<usize>> = (0..100_000usize).map(|j| j.checked_sub(1)).collect();
    let walk = skeleton(&parents).depth_first();
    assert_eq!(walk.len(), 100_000);
    assert!(walk.iter().enumerate().all(|(i, &(j, depth))| j == i && depth == i));
}
