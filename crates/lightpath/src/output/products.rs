//! One render written as several files: a USD stage's render products, each holding its
//! own AOVs. The render has one film with every product's AOVs; each product's file is
//! cut from it, so a checkpoint (of the one film) resumes them all.
//!
//! Which file holds what: the beauty (R, G, B, A), its light-group parts, the AOVs no
//! product names (the command line's) and Cryptomatte go to the first product holding
//! the beauty; every other AOV to each product naming it; an AOV's variance and its
//! light-group parts go with it.

use super::naming::OutputPaths;
use crate::aov::naming::BEAUTY;
use crate::film::Film;
use crate::scene::desc::ProductDesc;
use crate::scene::Aov;
use std::path::{Path, PathBuf};

/// One product's file and what it holds.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct ProductPlan {
    pub paths: OutputPaths,
    /// Indices of the render's AOVs it holds, in the render's order.
    pub aovs: Vec<usize>,
    /// It holds the beauty and alpha (and the PNG preview is of it).
    pub beauty: bool,
    /// It holds the Cryptomatte layers (the first product with the beauty).
    pub mattes: bool,
}

/// Where each product goes: its `productName`, or that name's file name in `dir` (a `-o`
/// naming a directory).
pub fn product_paths(products: &[ProductDesc], dir: Option<&Path>) -> Vec<OutputPaths> {
    products
        .iter()
        .map(|p| {
            let exr: PathBuf = match dir {
                Some(d) => d.join(p.output.file_name().unwrap_or(p.output.as_os_str())),
                None => p.output.clone(),
            };
            super::naming::output_paths("", Some(&exr))
        })
        .collect()
}

/// Which of the render's `aovs` each product holds (`paths` in the order of `products`).
pub fn assign(products: &[ProductDesc], paths: &[OutputPaths], aovs: &[Aov]) -> Vec<ProductPlan> {
    let primary = products.iter().position(|p| p.beauty).unwrap_or(0);
    let mut plans: Vec<ProductPlan> = products
        .iter()
        .zip(paths)
        .enumerate()
        .map(|(i, (p, paths))| ProductPlan {
            paths: paths.clone(),
            aovs: Vec::new(),
            beauty: p.beauty || i == primary,
            mattes: i == primary,
        })
        .collect();
    for (k, aov) in aovs.iter().enumerate() {
        // A part of a split goes where its whole goes (the whole comes first).
        let whole = aov.part_of.map_or(k, |w| w as usize);
        let name = &aovs.get(whole).unwrap_or(aov).name;
        let mut placed = false;
        for (plan, p) in plans.iter_mut().zip(products) {
            let holds = if name == BEAUTY {
                plan.beauty
            } else {
                p.aovs.contains(name)
            };
            if holds {
                plan.aovs.push(k);
                placed = true;
            }
        }
        if !placed {
            if let Some(plan) = plans.get_mut(primary) {
                plan.aovs.push(k);
            }
        }
    }
    plans
}

/// The film and AOVs of one product, cut from the render's (its AOVs' planes and their
/// squares, alpha, the sample counts; the Cryptomatte layers when it holds them).
pub fn product_film(film: &Film, aovs: &[Aov], plan: &ProductPlan) -> (Film, Vec<Aov>) {
    let new_index = |k: u32| plan.aovs.iter().position(|&j| j == k as usize);
    let mut planes = Vec::with_capacity(Film::stride_with(plan.aovs.len(), film.squared.len()));
    for &k in &plan.aovs {
        planes.extend(film.planes[3 * k..3 * k + 3].iter().cloned());
    }
    let mut squared = Vec::new();
    for (j, &k) in film.squared.iter().enumerate() {
        if let Some(n) = new_index(k) {
            let at = 3 * (film.aovs + j);
            planes.extend(film.planes[at..at + 3].iter().cloned());
            squared.push(n as u32);
        }
    }
    planes.push(film.planes[Film::alpha_slot(film.planes.len())].clone());
    let sub = Film {
        width: film.width,
        height: film.height,
        aovs: plan.aovs.len(),
        spp: film.spp,
        planes,
        sample_counts: film.sample_counts.clone(),
        squared,
        window: film.window,
        frame: film.frame,
        mattes: if plan.mattes {
            film.mattes.clone()
        } else {
            None
        },
    };
    let sub_aovs = plan
        .aovs
        .iter()
        .map(|&k| {
            let a = &aovs[k];
            Aov {
                name: a.name.clone(),
                definition: a.definition.clone(),
                expression: a.expression.clone(),
                flags: a.flags,
                split_base: a.split_base.and_then(new_index).map(|n| n as u32),
                part_of: a.part_of.and_then(new_index).map(|n| n as u32),
            }
        })
        .collect();
    (sub, sub_aovs)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn aov(name: &str, part_of: Option<u32>) -> Aov {
        Aov {
            name: name.into(),
            definition: format!("lpe:{name}"),
            expression: String::new(),
            flags: Default::default(),
            split_base: None,
            part_of,
        }
    }

    fn product(out: &str, aovs: &[&str], beauty: bool) -> ProductDesc {
        ProductDesc {
            output: out.into(),
            aovs: aovs.iter().map(|s| s.to_string()).collect(),
            beauty,
        }
    }

    #[test]
    fn each_product_holds_its_aovs_and_the_first_with_beauty_the_rest() {
        let products = [
            product("aovs.exr", &["diffuse", "N"], false),
            product("beauty.exr", &[], true),
        ];
        let aovs = [
            aov("beauty", None),
            aov("diffuse", None),
            aov("N", None),
            aov("extra", None),
            aov("beauty_key", Some(0)),
            aov("diffuse_key", Some(1)),
        ];
        let paths = product_paths(&products, Some(Path::new("out")));
        assert_eq!(paths[0].exr, PathBuf::from("out/aovs.exr"));
        assert_eq!(paths[1].png, PathBuf::from("out/beauty.png"));
        let plans = assign(&products, &paths, &aovs);
        assert_eq!(plans[0].aovs, vec![1, 2, 5]);
        assert_eq!(plans[1].aovs, vec![0, 3, 4]);
        assert!(!plans[0].beauty && plans[1].beauty && plans[1].mattes);

        let mut film = Film::with_squares(2, 1, aovs.len(), 4, vec![5, 3]);
        for (i, p) in film.planes.iter_mut().enumerate() {
            p.fill(i as f32);
        }
        let (sub, sub_aovs) = product_film(&film, &aovs, &plans[0]);
        let names: Vec<&str> = sub_aovs.iter().map(|a| a.name.as_str()).collect();
        assert_eq!(names, ["diffuse", "N", "diffuse_key"]);
        assert_eq!(sub_aovs[2].part_of, Some(0));
        // diffuse (planes 3-5), N (6-8), diffuse_key (15-17), its square (18-20), alpha.
        let firsts: Vec<f32> = sub.planes.iter().map(|p| p[0]).collect();
        assert_eq!(
            firsts,
            [3., 4., 5., 6., 7., 8., 15., 16., 17., 18., 19., 20., 24.]
        );
        assert_eq!(sub.squared, vec![2]);
        let (sub, _) = product_film(&film, &aovs, &plans[1]);
        // The square of `extra` (index 3 in the render, 1 here) is the second one.
        assert_eq!(sub.squared, vec![1]);
        assert_eq!(sub.planes[3 * 3][0], 21.0);
    }
}
