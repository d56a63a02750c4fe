//! Print Tables II and III and Fig. 3 at a chosen scale: `cargo run --release -p pf-mpf
//! --example tables -- quick|default|full`.
use pf_mpf::experiments::{Fig3Config, Scale, TableConfig, fig3, table2, table3};

fn main() -> Result<(), pf_mpf::error::MpfError> {
    let scale = match std::env::args().nth(1).as_deref() {
        Some("full") => Scale::Full,
        Some("default") => Scale::Default,
        _ => Scale::Quick,
    };
    let cfg = TableConfig::at(scale);
    for (title, rep) in [("Table II", table2(&cfg)?), ("Table III", table3(&cfg)?)] {
        println!("{title} (target {:.4}); ours | paper", rep.target);
        for (ours, paper) in rep.table.partitions.iter().zip(&rep.paper.partitions) {
            println!(
                "{}  N {:5} | {:5}  pos {:6.2} | {:5.2}  vel {:5.2} | {:5.2}  acc {:5.3} | {:4.2}  time {:.4} | {:.2}",
                ours.name,
                ours.n,
                paper.n,
                ours.rmse_pos,
                paper.rmse_pos,
                ours.rmse_vel,
                paper.rmse_vel,
                ours.rmse_acc,
                paper.rmse_acc,
                ours.time_s,
                paper.time_s
            );
        }
    }
    let f = fig3(&Fig3Config::at(scale))?;
    println!("Fig. 3: {:?}", f.calibration);
    for r in &f.rows {
        println!(
            "{}  predicted {:.4}  measured {:.4}  rel {:+.2}",
            r.name, r.predicted_s, r.measured_s, r.rel_error
        );
    }
    Ok(())
}
