//! FMI 3.0 instances side by side and on threads.

use super::*;

// ---------------------------------------------------------------------------------------------
// Instances and threads

pub fn fmi3_interleaved_instances_and_instances_on_threads_match_a_single_run(fmu: &Fmu3) {
    let h = fmu.step_size();
    for me in [false, true] {
        if (me && fmu.md.me.is_none()) || (!me && fmu.md.cs.is_none()) {
            continue;
        }
        let steps = 50;
        let reference = run(fmu, me, steps, h);
        // interleaved: three instances, one with other inputs
        let mut a = if me { Inst::me(fmu) } else { Inst::cs(fmu) };
        let mut b = if me { Inst::me(fmu) } else { Inst::cs(fmu) };
        let mut c = if me { Inst::me(fmu) } else { Inst::cs(fmu) };
        excite(&a);
        excite(&c);
        for (v, x) in excitation(fmu) {
            let minus: Vec<f64> = x.iter().map(|x| -x).collect();
            assert_eq!(b.set_f64(&[v.vr], &minus), fmi3OK, "{}: {}", fmu.id, b.log_text());
        }
        a.initialize();
        b.initialize();
        c.initialize();
        for (n, expected) in reference.iter().enumerate() {
            a.step(h);
            b.step(h);
            c.step(h);
            assert_eq!(
                a.observe(),
                *expected,
                "{}: interleaved instance a differs from a single run at step {n}",
                fmu.id
            );
            assert_eq!(
                c.observe(),
                *expected,
                "{}: interleaved instance c differs at step {n}",
                fmu.id
            );
        }
        drop((a, b, c));
        // threads
        let results: Vec<Vec<Vec<u64>>> = std::thread::scope(|s| {
            let handles: Vec<_> = (0..4).map(|_| s.spawn(|| run(fmu, me, steps, h))).collect();
            handles
                .into_iter()
                .map(|h| h.join().unwrap_or_else(|_| panic!("a thread's run panicked")))
                .collect()
        });
        for (k, r) in results.iter().enumerate() {
            assert!(
                *r == reference,
                "{}: the run on thread {k} differs from the sequential run ({})",
                fmu.id,
                if me { "ME" } else { "CS" }
            );
        }
    }
    info("3 interleaved instances and 4 threads, per interface, bit-identical");
}

// SAFETY: an Fmu3 is its description, its folders and the library's function pointers, which
// any thread may call; what holds raw pointers is the Inst, and the runs on threads each make
// their own instance.
unsafe impl Sync for Fmu3 {}
