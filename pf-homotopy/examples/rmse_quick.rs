//! Fig. 3 at the quick scale: prints the final RMS position error of each filter.
use pf_homotopy::experiments::{RmseConfig, Scale, rmse};

fn main() -> Result<(), pf_homotopy::HomotopyError> {
    let res = rmse(&RmseConfig::at_scale(Scale::Quick))?;
    let last = |v: &Vec<f64>| *v.last().unwrap_or(&f64::NAN);
    println!("final RMS position error (m) and seconds per run:");
    println!(
        "OHF     {:10.1} {:8.3}",
        last(&res.rmse.ohf),
        res.seconds_per_run.ohf
    );
    println!(
        "AOHF    {:10.1} {:8.3}",
        last(&res.rmse.aohf),
        res.seconds_per_run.aohf
    );
    println!(
        "UKF-LPC {:10.1} {:8.3}",
        last(&res.rmse.ukf_lpc),
        res.seconds_per_run.ukf_lpc
    );
    println!(
        "PF      {:10.1} {:8.3}",
        last(&res.rmse.pf),
        res.seconds_per_run.pf
    );
    for (k, t) in res.time.iter().enumerate() {
        println!(
            "{t:4} {:9.1} {:9.1} {:9.1} {:9.1}",
            res.rmse.ohf[k], res.rmse.aohf[k], res.rmse.ukf_lpc[k], res.rmse.pf[k]
        );
    }
    Ok(())
}
